//! A NOR flash made of RAM: the settings store of the emulator images (QEMU does not model
//! the STM32's flash controller, so its flash cannot be erased or programmed).
//!
//! What it is: `embedded-storage-async`'s `NorFlash` over a byte region that keeps its
//! contents across a reset (the images place it where neither QEMU's `system_reset` nor
//! cortex-m-rt's start-up writes: docs/firmware.md "Settings"). It behaves as NOR flash does:
//! an erase sets a page to 0xFF, a write can only clear bits (the stored byte is old AND new).
//! A region that was never formatted (QEMU starts RAM at zero) is erased once, like a new
//! chip's flash, and marked formatted by a word past the pages.
//!
//! What it is not: the board's store (the F405's flash sectors, src/chip/flash.rs).

use embedded_storage_async::nor_flash::{ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash};

/// The word past the pages once the region has been formatted.
pub const FORMATTED: u32 = 0x4643_4647;

/// The emulator images' store: three 16 KiB pages (the board's sector geometry), then the
/// formatted mark.
pub const PAGE: usize = 16 * 1024;
pub const PAGES: usize = 3;
/// Where it is on the F405 image: QEMU's netduinoplus2 maps 192 KiB of SRAM from 0x2000_0000
/// (and no CCM); memory.x gives the program the chip's 128 KiB, the store takes the RAM above.
pub const F405_BASE: usize = 0x2002_0000;

/// Out of the region, or not on a page boundary.
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct RamFlashError(NorFlashErrorKind);

impl NorFlashError for RamFlashError {
    fn kind(&self) -> NorFlashErrorKind {
        self.0
    }
}

/// `PAGE`-byte erase pages over `mem` (its length a multiple of `PAGE`).
pub struct RamFlash<const PAGE: usize> {
    mem: &'static mut [u8],
}

impl<const PAGE: usize> RamFlash<PAGE> {
    /// The pages `mem` and the formatted mark `mark`: erased first if `mark` is not set.
    pub fn new(mem: &'static mut [u8], mark: &'static mut u32) -> Self {
        if *mark != FORMATTED {
            mem.fill(0xFF);
            *mark = FORMATTED;
        }
        RamFlash { mem }
    }

    fn range(&self, offset: u32, len: usize) -> Result<core::ops::Range<usize>, RamFlashError> {
        let a = offset as usize;
        match a.checked_add(len) {
            Some(b) if b <= self.mem.len() => Ok(a..b),
            _ => Err(RamFlashError(NorFlashErrorKind::OutOfBounds)),
        }
    }
}

impl<const PAGE: usize> ErrorType for RamFlash<PAGE> {
    type Error = RamFlashError;
}

impl<const PAGE: usize> ReadNorFlash for RamFlash<PAGE> {
    const READ_SIZE: usize = 1;
    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        let r = self.range(offset, bytes.len())?;
        bytes.copy_from_slice(&self.mem[r]);
        Ok(())
    }
    fn capacity(&self) -> usize {
        self.mem.len()
    }
}

impl<const PAGE: usize> NorFlash for RamFlash<PAGE> {
    const WRITE_SIZE: usize = 1;
    const ERASE_SIZE: usize = PAGE;
    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        if !(from as usize).is_multiple_of(PAGE) || !(to as usize).is_multiple_of(PAGE) || to < from {
            return Err(RamFlashError(NorFlashErrorKind::NotAligned));
        }
        let r = self.range(from, (to - from) as usize)?;
        self.mem[r].fill(0xFF);
        Ok(())
    }
    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        let r = self.range(offset, bytes.len())?;
        for (m, &b) in self.mem[r].iter_mut().zip(bytes) {
            *m &= b;
        }
        Ok(())
    }
}
