//! The settings store's flash on each image (feature `settings`; docs/firmware.md "Settings").
//!
//! - Board (`hw`): flash sectors 1-3 of the F405 (three 16 KiB erase sectors that
//!   memory.x leaves out of the program) as the store's pages, erased one at a time
//!   (`crate::flash_ctl::SectorFlash`: the controller's sequences, host-tested; here only
//!   FLASH's registers and the loads and stores). An erase stalls the CPU, the control tick
//!   included, for at most 0.5 s a sector at x32: inside the watchdog's shortest timeout,
//!   fed by the tick between sectors (docs/firmware.md "Settings").
//! - QEMU (`qemu`): QEMU does not model the flash controller, so the store is RAM
//!   ([`crate::flash_ram::RamFlash`]) at a fixed address that no ELF segment covers:
//!   QEMU's `system_reset` rewrites only the ELF's segments (and zero-fills their .bss
//!   part), cortex-m-rt's start-up only .data and .bss, so the store survives a reset. The F405
//!   image uses the 64 KiB of SRAM QEMU maps above memory.x's 128 KiB (0x2002_0000).
//!
//! Not here: the record and the map (src/settings.rs), the commands (src/app/config.rs).

use crate::settings::FlashStore;

/// The store's pages: three of 16 KiB (the F405's sectors 1-3 on the board).
pub use crate::flash_ram::{PAGE, PAGES};

#[cfg(feature = "qemu")]
pub type StoreFlash = crate::flash_ram::RamFlash<PAGE>;
#[cfg(feature = "hw")]
pub type StoreFlash = crate::flash_ctl::SectorFlash<F405Flash>;

/// The emulator's store: RAM past memory.x's (F405 image), the pages then the formatted mark.
#[cfg(feature = "qemu")]
pub const SETTINGS_RAM: usize = crate::flash_ram::F405_BASE;

/// The store on this image, once (None if called again).
#[cfg(feature = "qemu")]
pub fn store(_flash: stm32f4xx_hal::pac::FLASH) -> Option<&'static mut FlashStore<StoreFlash>> {
    // SAFETY: [SETTINGS_RAM, + PAGES x PAGE + 4) is RAM on the emulated chip that nothing else
    // in the image addresses (past memory.x's RAM region), taken once (the singleton).
    let (mem, mark) = unsafe { (core::slice::from_raw_parts_mut(SETTINGS_RAM as *mut u8, PAGES * PAGE), &mut *((SETTINGS_RAM + PAGES * PAGE) as *mut u32)) };
    let flash = crate::flash_ram::RamFlash::<PAGE>::new(mem, mark);
    cortex_m::singleton!(: FlashStore<StoreFlash> = FlashStore::new(flash, 0..(PAGES * PAGE) as u32))
}

#[cfg(feature = "hw")]
pub use hw::*;

#[cfg(feature = "hw")]
mod hw {
    use super::*;
    use crate::flash_ctl::{FlashRegs, SectorFlash};
    use stm32f4xx_hal::pac;

    /// FLASH's registers and the flash itself: the controller's sequences are
    /// `crate::flash_ctl`'s (host-tested); this is loads and stores.
    pub struct F405Flash(pac::FLASH);

    pub fn store(flash: pac::FLASH) -> Option<&'static mut FlashStore<StoreFlash>> {
        let f = SectorFlash::new(F405Flash(flash));
        cortex_m::singleton!(: FlashStore<StoreFlash> = FlashStore::new(f, 0..(PAGES * PAGE) as u32))
    }

    // SAFETY (every `bits` below): whole-register values of RM0090's fields (crate::flash_ctl).
    impl FlashRegs for F405Flash {
        fn sr(&mut self) -> u32 {
            self.0.sr().read().bits()
        }
        fn write_sr(&mut self, v: u32) {
            unsafe { self.0.sr().write(|w| w.bits(v)) };
        }
        fn cr(&mut self) -> u32 {
            self.0.cr().read().bits()
        }
        fn write_cr(&mut self, v: u32) {
            unsafe { self.0.cr().write(|w| w.bits(v)) };
        }
        fn write_keyr(&mut self, v: u32) {
            unsafe { self.0.keyr().write(|w| w.bits(v)) };
        }
        fn acr(&mut self) -> u32 {
            self.0.acr().read().bits()
        }
        fn write_acr(&mut self, v: u32) {
            unsafe { self.0.acr().write(|w| w.bits(v)) };
        }
        fn read_mem(&mut self, addr: u32, out: &mut [u8]) {
            for (k, b) in out.iter_mut().enumerate() {
                // SAFETY: a load from the store's sectors (SectorFlash checks the bounds)
                *b = unsafe { core::ptr::read_volatile((addr as usize + k) as *const u8) };
            }
        }
        fn write_mem(&mut self, addr: u32, byte: u8) {
            // SAFETY: a store to the store's sectors with CR.PG set: it programs the byte
            unsafe { core::ptr::write_volatile(addr as usize as *mut u8, byte) };
        }
    }
}
