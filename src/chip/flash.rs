//! The settings store's flash on each image (feature `settings`; docs/firmware.md "Settings").
//!
//! - Board (`hw`): flash sectors 1-3 of the F405 (three 16 KiB erase sectors that
//!   memory.x leaves out of the program), through the HAL's flash driver (stm32f4xx-hal's
//!   `UnlockedFlash`, its `embedded-storage` NorFlash). The HAL's NorFlash erases in 128 KiB
//!   units (its largest sector); [`SectorFlash`] offers the three 16 KiB sectors as pages and
//!   erases one at a time (an erase stalls the CPU, the control tick included, for at most the
//!   datasheet's 0.8 s a sector: inside the 1 s watchdog, fed by the tick between sectors).
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
pub type StoreFlash = SectorFlash;

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
    use embedded_storage_async::nor_flash::{ErrorType, NorFlash, ReadNorFlash};
    use stm32f4xx_hal::flash::{Error, FlashExt, LockedFlash};
    #[allow(unused_imports)]
    use FlashExt as _;

    /// The store's first byte: sector 1 (memory.x `_settings_flash_start`), as an offset
    /// from the start of flash.
    const BASE: u32 = 0x4000;

    /// Flash sectors 1-3 as `PAGE`-byte pages, offsets from sector 1.
    pub struct SectorFlash(LockedFlash);

    pub fn store(flash: stm32f4xx_hal::pac::FLASH) -> Option<&'static mut FlashStore<StoreFlash>> {
        let f = SectorFlash(LockedFlash::new(flash));
        cortex_m::singleton!(: FlashStore<StoreFlash> = FlashStore::new(f, 0..(PAGES * PAGE) as u32))
    }

    impl ErrorType for SectorFlash {
        type Error = Error;
    }

    impl ReadNorFlash for SectorFlash {
        const READ_SIZE: usize = 1;
        async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Error> {
            embedded_storage::nor_flash::ReadNorFlash::read(&mut self.0, BASE + offset, bytes)
        }
        fn capacity(&self) -> usize {
            PAGES * PAGE
        }
    }

    impl NorFlash for SectorFlash {
        const WRITE_SIZE: usize = 1;
        const ERASE_SIZE: usize = PAGE;
        async fn erase(&mut self, from: u32, to: u32) -> Result<(), Error> {
            let mut a = from;
            while a < to && a < (PAGES * PAGE) as u32 {
                embedded_storage::nor_flash::NorFlash::erase(&mut self.0.unlocked(), BASE + a, BASE + a + PAGE as u32)?;
                a += PAGE as u32;
            }
            Ok(())
        }
        async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Error> {
            if offset as usize + bytes.len() > PAGES * PAGE {
                return Err(Error::ProgrammingAlignment);
            }
            embedded_storage::nor_flash::NorFlash::write(&mut self.0.unlocked(), BASE + offset, bytes)
        }
    }
}
