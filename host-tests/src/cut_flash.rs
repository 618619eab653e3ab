//! A NOR flash on the host whose power can be cut after any byte written or erased: the
//! settings store's power-cut tests (tests/settings_store.rs) and its wear figures
//! (examples/settings_wear.rs).
//!
//! NOR semantics as the F405's: an erase sets a page to 0xFF, a write can only clear bits.
//! A cut stops the operation in flight after `budget` more bytes: the bytes before it are done,
//! the byte at the cut is torn (a write leaves `old AND new AND noise`, an erase `old OR
//! noise`), the rest untouched; every later operation fails until [`CutFlash::power_on`].
//! Shared by handle (`Rc`): a board built on it and the test that cuts and inspects it.
use std::cell::RefCell;
use std::rc::Rc;

use embedded_storage_async::nor_flash::{ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash};

/// The power went (or an address out of the flash).
#[derive(Debug, Clone, Copy, PartialEq, Eq)]
pub struct Cut;

impl NorFlashError for Cut {
    fn kind(&self) -> NorFlashErrorKind {
        NorFlashErrorKind::Other
    }
}

#[derive(Debug, Clone)]
pub struct State {
    pub mem: Vec<u8>,
    /// Bytes (written or erased) until the cut; None: no cut coming.
    pub budget: Option<u64>,
    /// The power is off: every operation fails.
    pub off: bool,
    /// The torn byte's noise.
    pub noise: u8,
    /// Erases per page, bytes written and erased in all.
    pub page_erases: Vec<u64>,
    pub bytes_written: u64,
    pub bytes_erased: u64,
}

/// `page`-byte pages; cloning the handle shares the flash.
#[derive(Clone)]
pub struct CutFlash<const PAGE: usize> {
    pub state: Rc<RefCell<State>>,
}

impl<const PAGE: usize> CutFlash<PAGE> {
    /// `pages` erased pages, no cut.
    pub fn new(pages: usize) -> Self {
        let s = State { mem: vec![0xFF; pages * PAGE], budget: None, off: false, noise: 0x5A, page_erases: vec![0; pages], bytes_written: 0, bytes_erased: 0 };
        CutFlash { state: Rc::new(RefCell::new(s)) }
    }
    /// A flash with a copy of this one's state (not shared).
    pub fn fork(&self) -> Self {
        CutFlash { state: Rc::new(RefCell::new(self.state.borrow().clone())) }
    }
    /// Cut the power after `bytes` more bytes written or erased, tearing the next one with
    /// `noise`.
    pub fn cut_after(&self, bytes: u64, noise: u8) {
        let mut s = self.state.borrow_mut();
        s.budget = Some(bytes);
        s.noise = noise;
    }
    /// Power back: operations work again, no cut coming.
    pub fn power_on(&self) {
        let mut s = self.state.borrow_mut();
        s.off = false;
        s.budget = None;
    }
    pub fn is_off(&self) -> bool {
        self.state.borrow().off
    }
    /// Bytes written plus bytes erased so far (what a cut counts).
    pub fn bytes_moved(&self) -> u64 {
        let s = self.state.borrow();
        s.bytes_written + s.bytes_erased
    }
    pub fn bytes(&self) -> Vec<u8> {
        self.state.borrow().mem.clone()
    }
    pub fn set_bytes(&self, b: &[u8]) {
        self.state.borrow_mut().mem.copy_from_slice(b);
    }

    /// One byte of an operation: Ok(true) do it, Ok(false) tear it and cut.
    fn step(s: &mut State) -> Result<bool, Cut> {
        if s.off {
            return Err(Cut);
        }
        match s.budget {
            Some(0) => {
                s.off = true;
                Ok(false)
            }
            Some(ref mut n) => {
                *n -= 1;
                Ok(true)
            }
            None => Ok(true),
        }
    }
}

impl<const PAGE: usize> ErrorType for CutFlash<PAGE> {
    type Error = Cut;
}

impl<const PAGE: usize> ReadNorFlash for CutFlash<PAGE> {
    const READ_SIZE: usize = 1;
    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Cut> {
        let s = self.state.borrow();
        if s.off {
            return Err(Cut);
        }
        let a = offset as usize;
        bytes.copy_from_slice(s.mem.get(a..a + bytes.len()).ok_or(Cut)?);
        Ok(())
    }
    fn capacity(&self) -> usize {
        self.state.borrow().mem.len()
    }
}

impl<const PAGE: usize> NorFlash for CutFlash<PAGE> {
    const WRITE_SIZE: usize = 1;
    const ERASE_SIZE: usize = PAGE;
    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Cut> {
        let mut s = self.state.borrow_mut();
        let (a, b) = (from as usize, to as usize);
        assert!(a % PAGE == 0 && b % PAGE == 0 && b <= s.mem.len(), "erase {a}..{b} off the pages");
        for page in a / PAGE..b / PAGE {
            s.page_erases[page] += 1;
            for i in page * PAGE..(page + 1) * PAGE {
                if !Self::step(&mut s)? {
                    let n = s.noise;
                    s.mem[i] |= n;
                    return Err(Cut);
                }
                s.mem[i] = 0xFF;
                s.bytes_erased += 1;
            }
        }
        Ok(())
    }
    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Cut> {
        let mut s = self.state.borrow_mut();
        let a = offset as usize;
        assert!(a + bytes.len() <= s.mem.len(), "write off the pages");
        for (i, &b) in bytes.iter().enumerate() {
            if !Self::step(&mut s)? {
                let n = s.noise;
                s.mem[a + i] &= b | n;
                return Err(Cut);
            }
            s.mem[a + i] &= b;
            s.bytes_written += 1;
        }
        Ok(())
    }
}
