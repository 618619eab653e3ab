//! The F405's flash controller, its sequences (RM0090 §3.5-3.6): a sector erase at x32
//! parallelism, byte programming at x8, the error flags cleared before each operation, the
//! ART accelerator's caches reset after each (§3.5.2: a cache line read before an erase
//! would be read again after it), the controller locked between operations. Over a small
//! register trait ([`FlashRegs`]): `chip::flash` implements it over FLASH's registers and
//! the flash itself (board build); the host tests over a mock whose data cache keeps what
//! it read (host-tests/tests/flash_ctl.rs).
//!
//! [`SectorFlash`] (feature `settings`): three 16 KiB sectors as the settings store's pages.

/// FLASH_SR: end of operation, the error flags (rc_w1), busy.
pub const SR_EOP: u32 = 1 << 0;
pub const SR_OPERR: u32 = 1 << 1;
pub const SR_WRPERR: u32 = 1 << 4;
pub const SR_PGAERR: u32 = 1 << 5;
pub const SR_PGPERR: u32 = 1 << 6;
pub const SR_PGSERR: u32 = 1 << 7;
pub const SR_ERRORS: u32 = SR_OPERR | SR_WRPERR | SR_PGAERR | SR_PGPERR | SR_PGSERR;
pub const SR_BSY: u32 = 1 << 16;
/// FLASH_CR: program, sector erase, the sector number, the parallelism, start, lock.
pub const CR_PG: u32 = 1 << 0;
pub const CR_SER: u32 = 1 << 1;
pub const CR_SNB_SHIFT: u32 = 3;
pub const CR_PSIZE_SHIFT: u32 = 8;
pub const CR_PSIZE_MASK: u32 = 0b11 << CR_PSIZE_SHIFT;
/// PSIZE x8 (a byte a write) and x32 (a word: 2.7-3.6 V only; a 16 KiB sector erases in
/// 0.5 s at most, against 0.8 s at x8: DS8626 t_ERASE16KB).
pub const CR_PSIZE_X8: u32 = 0b00 << CR_PSIZE_SHIFT;
pub const CR_PSIZE_X32: u32 = 0b10 << CR_PSIZE_SHIFT;
pub const CR_STRT: u32 = 1 << 16;
pub const CR_LOCK: u32 = 1 << 31;
/// FLASH_ACR: the instruction and data caches, on and reset (a reset only while off).
pub const ACR_ICEN: u32 = 1 << 9;
pub const ACR_DCEN: u32 = 1 << 10;
pub const ACR_ICRST: u32 = 1 << 11;
pub const ACR_DCRST: u32 = 1 << 12;
/// FLASH_KEYR's unlock sequence.
pub const KEY1: u32 = 0x4567_0123;
pub const KEY2: u32 = 0xCDEF_89AB;
/// The flash's first byte on the bus.
pub const FLASH_BASE: u32 = 0x0800_0000;

/// The worst 16 KiB sector erase at x32 parallelism, s (DS8626 t_ERASE16KB, 2.7-3.6 V).
pub const ERASE_16K_MAX_S: f32 = 0.5;

/// The flash controller's registers and the flash as the CPU reads it (through the caches).
pub trait FlashRegs {
    fn sr(&mut self) -> u32;
    /// FLASH_SR: a 1 clears that flag.
    fn write_sr(&mut self, v: u32);
    fn cr(&mut self) -> u32;
    fn write_cr(&mut self, v: u32);
    fn write_keyr(&mut self, v: u32);
    fn acr(&mut self) -> u32;
    fn write_acr(&mut self, v: u32);
    /// The bytes at bus address `addr`, as a load reads them.
    fn read_mem(&mut self, addr: u32, out: &mut [u8]);
    /// A byte store at bus address `addr` (programs it while CR.PG is set).
    fn write_mem(&mut self, addr: u32, byte: u8);
}

/// What FLASH_SR reported after an operation (or the controller stayed locked).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FlashError {
    Sequence,
    Parallelism,
    Alignment,
    WriteProtection,
    Operation,
    Locked,
    /// Past the store's pages (a caller's bug, refused before any register is touched).
    OutOfBounds,
}

impl FlashError {
    /// The first error flag set in `sr`, if any.
    pub fn of_sr(sr: u32) -> Option<FlashError> {
        [
            (SR_PGSERR, FlashError::Sequence),
            (SR_PGPERR, FlashError::Parallelism),
            (SR_PGAERR, FlashError::Alignment),
            (SR_WRPERR, FlashError::WriteProtection),
            (SR_OPERR, FlashError::Operation),
        ]
        .into_iter()
        .find(|&(bit, _)| sr & bit != 0)
        .map(|(_, e)| e)
    }
}

/// The controller's sequences over `R`.
pub struct FlashCtl<R> {
    pub regs: R,
}

impl<R: FlashRegs> FlashCtl<R> {
    pub fn new(regs: R) -> Self {
        FlashCtl { regs }
    }

    fn wait_idle(&mut self) {
        while self.regs.sr() & SR_BSY != 0 {}
    }

    /// Before an operation: idle, the flags a past operation left cleared (else its error
    /// would be read as this one's), unlocked.
    fn begin(&mut self) -> Result<(), FlashError> {
        self.wait_idle();
        self.regs.write_sr(SR_EOP | SR_ERRORS);
        if self.regs.cr() & CR_LOCK != 0 {
            self.regs.write_keyr(KEY1);
            self.regs.write_keyr(KEY2);
        }
        if self.regs.cr() & CR_LOCK != 0 {
            return Err(FlashError::Locked);
        }
        Ok(())
    }

    /// After an operation: idle, its flags read and cleared, SER/PG off and locked, the
    /// caches reset.
    fn end(&mut self) -> Result<(), FlashError> {
        self.wait_idle();
        let sr = self.regs.sr();
        self.regs.write_sr(sr & (SR_EOP | SR_ERRORS));
        self.regs.write_cr(CR_LOCK);
        self.flush_caches();
        FlashError::of_sr(sr).map_or(Ok(()), Err)
    }

    /// Reset the instruction and data caches (RM0090 §3.5.2: each only while it is off),
    /// then turn on again whichever was on.
    pub fn flush_caches(&mut self) {
        let acr = self.regs.acr();
        let off = acr & !(ACR_ICEN | ACR_DCEN);
        self.regs.write_acr(off);
        self.regs.write_acr(off | ACR_ICRST | ACR_DCRST);
        self.regs.write_acr(off);
        self.regs.write_acr(acr & !(ACR_ICRST | ACR_DCRST));
    }

    /// Erase sector `snb` at x32 parallelism.
    pub fn erase_sector(&mut self, snb: u8) -> Result<(), FlashError> {
        self.begin()?;
        let cr = CR_PSIZE_X32 | CR_SER | ((snb as u32 & 0xF) << CR_SNB_SHIFT);
        self.regs.write_cr(cr);
        self.regs.write_cr(cr | CR_STRT);
        self.end()
    }

    /// Program `bytes` at bus address `addr`, a byte at a time (x8); stops at the first error.
    pub fn program(&mut self, addr: u32, bytes: &[u8]) -> Result<(), FlashError> {
        self.begin()?;
        self.regs.write_cr(CR_PSIZE_X8 | CR_PG);
        for (k, &b) in bytes.iter().enumerate() {
            self.regs.write_mem(addr + k as u32, b);
            self.wait_idle();
            if self.regs.sr() & SR_ERRORS != 0 {
                break;
            }
        }
        self.end()
    }

    /// The bytes at bus address `addr`.
    pub fn read(&mut self, addr: u32, out: &mut [u8]) {
        self.regs.read_mem(addr, out);
    }
}

#[cfg(feature = "settings")]
pub use store::{SectorFlash, FIRST_SECTOR, STORE_OFFSET};

#[cfg(feature = "settings")]
mod store {
    use super::*;
    use crate::flash_ram::{PAGE, PAGES};
    use embedded_storage_async::nor_flash::{ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash};

    impl NorFlashError for FlashError {
        fn kind(&self) -> NorFlashErrorKind {
            match self {
                FlashError::OutOfBounds => NorFlashErrorKind::OutOfBounds,
                FlashError::Alignment => NorFlashErrorKind::NotAligned,
                _ => NorFlashErrorKind::Other,
            }
        }
    }

    /// Sectors `FIRST_SECTOR`.. (16 KiB each, from bus address `FLASH_BASE + STORE_OFFSET`) as the
    /// store's `PAGES` pages of `PAGE` bytes, offsets from the first.
    pub struct SectorFlash<R> {
        ctl: FlashCtl<R>,
    }

    /// The store's first byte: sector 1 (memory.x `_settings_flash_start`), from the flash's start.
    pub const STORE_OFFSET: u32 = 0x4000;
    /// Its first sector.
    pub const FIRST_SECTOR: u8 = 1;

    impl<R: FlashRegs> SectorFlash<R> {
        pub fn new(regs: R) -> Self {
            SectorFlash { ctl: FlashCtl::new(regs) }
        }
        pub fn ctl(&mut self) -> &mut FlashCtl<R> {
            &mut self.ctl
        }
        fn check(offset: u32, len: usize) -> Result<(), FlashError> {
            if offset as usize + len > PAGES * PAGE {
                return Err(FlashError::OutOfBounds);
            }
            Ok(())
        }
    }

    impl<R: FlashRegs> ErrorType for SectorFlash<R> {
        type Error = FlashError;
    }

    impl<R: FlashRegs> ReadNorFlash for SectorFlash<R> {
        const READ_SIZE: usize = 1;
        async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), FlashError> {
            Self::check(offset, bytes.len())?;
            self.ctl.read(FLASH_BASE + STORE_OFFSET + offset, bytes);
            Ok(())
        }
        fn capacity(&self) -> usize {
            PAGES * PAGE
        }
    }

    impl<R: FlashRegs> NorFlash for SectorFlash<R> {
        const WRITE_SIZE: usize = 1;
        const ERASE_SIZE: usize = PAGE;
        /// One sector at a time: an erase stalls every fetch from flash (the F405 has one
        /// bank), up to [`ERASE_16K_MAX_S`] each; the control tick that runs between two
        /// feeds the watchdog.
        async fn erase(&mut self, from: u32, to: u32) -> Result<(), FlashError> {
            if !from.is_multiple_of(PAGE as u32) || !to.is_multiple_of(PAGE as u32) || to < from {
                return Err(FlashError::Alignment);
            }
            Self::check(from, (to - from) as usize)?;
            for page in from / PAGE as u32..to / PAGE as u32 {
                self.ctl.erase_sector(FIRST_SECTOR + page as u8)?;
            }
            Ok(())
        }
        async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), FlashError> {
            Self::check(offset, bytes.len())?;
            self.ctl.program(FLASH_BASE + STORE_OFFSET + offset, bytes)
        }
    }
}
