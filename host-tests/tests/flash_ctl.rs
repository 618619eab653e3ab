//! The board's flash driver's sequences (src/flash_ctl.rs; its registers are src/chip/flash.rs,
//! which no test here runs: QEMU does not model the F405's flash controller) against a mock
//! of FLASH's registers and of the ART accelerator's data cache, which keeps the lines it read
//! until it is reset (RM0090 §3.5.2): an erase and a program are read back as written, a
//! failed operation does not fail the next, erases run at x32, the controller is locked
//! between operations; and the settings store over it saves, migrates and is read back. The
//! watchdog's margin over the slowest erase, across the LSI's range.
use std::collections::HashMap;

use finger_fw::board::{iwdg_timeout_s, LSI_MAX_HZ, LSI_MIN_HZ};
use finger_fw::flash_ctl::*;
use finger_fw::flash_ram::{PAGE, PAGES};
use finger_fw::settings::{ConfigStore, FlashStore, RECORD_MAX};

const LINE: u32 = 16;
/// The mock's flash: sectors 0-3 (16 KiB each), from FLASH_BASE.
const SIZE: usize = 4 * 16 * 1024;

/// FLASH's registers and the flash behind the data cache.
struct Mock {
    mem: Vec<u8>,
    sr: u32,
    cr: u32,
    acr: u32,
    key_seen: bool,
    /// line address -> the bytes the cache holds for it
    dcache: HashMap<u32, [u8; LINE as usize]>,
    /// the next operation fails with these SR flags (and does nothing)
    fail_next: u32,
    /// (sector, PSIZE) of each erase started
    erases: Vec<(u32, u32)>,
    /// CR.LOCK clear at any register write other than the unlock's and the lock's own
    unlocked_writes: u32,
}

impl Mock {
    fn new() -> Self {
        Mock {
            mem: vec![0xFF; SIZE],
            sr: 0,
            cr: CR_LOCK,
            acr: ACR_ICEN | ACR_DCEN | 5,
            key_seen: false,
            dcache: HashMap::new(),
            fail_next: 0,
            erases: Vec::new(),
            unlocked_writes: 0,
        }
    }
    fn idx(addr: u32) -> usize {
        (addr - FLASH_BASE) as usize
    }
}

impl FlashRegs for Mock {
    fn sr(&mut self) -> u32 {
        self.sr
    }
    fn write_sr(&mut self, v: u32) {
        self.sr &= !v;
    }
    fn cr(&mut self) -> u32 {
        self.cr
    }
    fn write_cr(&mut self, v: u32) {
        if self.cr & CR_LOCK != 0 {
            return; // locked: ignored
        }
        self.cr = v;
        if v & CR_STRT != 0 && v & CR_SER != 0 {
            self.cr &= !CR_STRT;
            let snb = (v >> CR_SNB_SHIFT) & 0xF;
            self.erases.push((snb, (v & CR_PSIZE_MASK) >> CR_PSIZE_SHIFT));
            if self.fail_next != 0 {
                self.sr |= std::mem::take(&mut self.fail_next);
                return;
            }
            let at = snb as usize * 16 * 1024;
            self.mem[at..at + 16 * 1024].fill(0xFF);
            self.sr |= SR_EOP;
        }
    }
    fn write_keyr(&mut self, v: u32) {
        if v == KEY1 {
            self.key_seen = true;
        } else if v == KEY2 && self.key_seen {
            self.cr &= !CR_LOCK;
        } else {
            self.key_seen = false;
        }
    }
    fn acr(&mut self) -> u32 {
        self.acr
    }
    fn write_acr(&mut self, v: u32) {
        // DCRST resets the data cache only while it is off
        if v & ACR_DCRST != 0 && self.acr & ACR_DCEN == 0 && v & ACR_DCEN == 0 {
            self.dcache.clear();
        }
        self.acr = v;
    }
    fn read_mem(&mut self, addr: u32, out: &mut [u8]) {
        for (k, b) in out.iter_mut().enumerate() {
            let a = addr + k as u32;
            if self.acr & ACR_DCEN == 0 {
                *b = self.mem[Mock::idx(a)];
                continue;
            }
            let line = a & !(LINE - 1);
            let mem = &self.mem;
            let cached = self.dcache.entry(line).or_insert_with(|| {
                let i = Mock::idx(line);
                mem[i..i + LINE as usize].try_into().unwrap()
            });
            *b = cached[(a - line) as usize];
        }
    }
    fn write_mem(&mut self, addr: u32, byte: u8) {
        if self.cr & CR_PG == 0 || self.cr & CR_LOCK != 0 {
            self.sr |= SR_PGSERR;
            return;
        }
        if (self.cr & CR_PSIZE_MASK) != CR_PSIZE_X8 {
            self.sr |= SR_PGPERR;
            return;
        }
        if self.fail_next != 0 {
            self.sr |= std::mem::take(&mut self.fail_next);
            return;
        }
        self.unlocked_writes += 1;
        // NOR: a program only clears bits; the cache is not told
        self.mem[Mock::idx(addr)] &= byte;
        self.sr |= SR_EOP;
    }
}

fn read(ctl: &mut FlashCtl<Mock>, addr: u32, n: usize) -> Vec<u8> {
    let mut v = vec![0; n];
    ctl.read(addr, &mut v);
    v
}

/// Bytes read (so cached), then erased: read back erased; programmed: read back as written.
/// The caches are on again after each operation, the controller locked.
#[test]
fn an_erase_and_a_program_read_back_through_the_data_cache() {
    let mut ctl = FlashCtl::new(Mock::new());
    let at = FLASH_BASE + 0x4000;
    ctl.program(at, b"page marker 1234").unwrap();
    assert_eq!(read(&mut ctl, at, 16), b"page marker 1234");
    assert!(!ctl.regs.dcache.is_empty(), "the read went through the cache");
    ctl.erase_sector(1).unwrap();
    assert_eq!(read(&mut ctl, at, 16), [0xFF; 16], "the erase read back through the cache");
    ctl.program(at + 3, b"xy").unwrap();
    assert_eq!(read(&mut ctl, at, 6), [0xFF, 0xFF, 0xFF, b'x', b'y', 0xFF], "the program read back");
    assert_eq!(ctl.regs.acr & (ACR_ICEN | ACR_DCEN | ACR_ICRST | ACR_DCRST | 0xF), ACR_ICEN | ACR_DCEN | 5, "caches on, not held in reset, wait states kept");
    assert_ne!(ctl.regs.cr & CR_LOCK, 0, "locked between operations");
    assert_eq!(ctl.regs.erases, [(1, 0b10)], "one erase of sector 1 at x32");
}

/// A failed erase or program reports its error once: the next operation, which succeeds,
/// reports success (a flag a past operation left, or the boot found, is cleared first).
#[test]
fn a_failed_operation_does_not_fail_the_next() {
    for (flag, err) in [(SR_WRPERR, FlashError::WriteProtection), (SR_OPERR, FlashError::Operation), (SR_PGSERR, FlashError::Sequence)] {
        let mut ctl = FlashCtl::new(Mock::new());
        ctl.regs.fail_next = flag;
        assert_eq!(ctl.erase_sector(2), Err(err));
        assert_eq!(ctl.erase_sector(2), Ok(()), "flag {flag:#x}: the erase after a failed one");
        ctl.regs.fail_next = flag;
        assert_eq!(ctl.program(FLASH_BASE + 0x8000, b"ab"), Err(err));
        assert_eq!(ctl.program(FLASH_BASE + 0x8000, b"ab"), Ok(()), "flag {flag:#x}: the program after a failed one");
        assert_eq!(read(&mut ctl, FLASH_BASE + 0x8000, 2), b"ab");
        // a flag already set before the first operation (left by a boot loader, a debugger)
        let mut ctl = FlashCtl::new(Mock::new());
        ctl.regs.sr = flag;
        assert_eq!(ctl.program(FLASH_BASE + 0x8000, b"c"), Ok(()));
        assert_eq!(ctl.regs.sr & SR_ERRORS, 0);
    }
}

/// The settings store over the three sectors, through the cache: saves that fill a page,
/// migrate to the next and erase one, each read back as the newest; `factory` erases all,
/// and the store reads empty.
#[test]
fn the_settings_store_over_the_sectors_reads_back_every_save() {
    let flash = SectorFlash::new(Mock::new());
    let store: &'static mut FlashStore<SectorFlash<Mock>> = Box::leak(Box::new(FlashStore::new(flash, 0..(PAGES * PAGE) as u32)));
    let mut buf = [0u8; RECORD_MAX];
    assert_eq!(store.read(&mut buf), Ok(None));
    let mut rec = [0u8; 200];
    for n in 0..300u32 {
        for (k, b) in rec.iter_mut().enumerate() {
            *b = (n as usize * 7 + k) as u8;
        }
        rec[..4].copy_from_slice(&n.to_le_bytes());
        store.write(&rec).unwrap_or_else(|e| panic!("save {n}: {e:?}"));
        let got = store.read(&mut buf).unwrap().unwrap();
        assert_eq!(&buf[..got], &rec[..], "save {n} read back");
    }
    let erases = store.flash().erases;
    assert!(erases >= 2, "the saves erased pages ({erases})");
    store.erase().unwrap();
    assert_eq!(store.read(&mut buf), Ok(None), "factory: empty");
    let mock = &mut store.flash().flash_mut().ctl().regs;
    assert!(mock.erases.iter().all(|&(s, p)| (1..=3).contains(&s) && p == 0b10), "sectors 1-3 only, at x32: {:?}", mock.erases);
    assert!(mock.mem[..0x4000].iter().all(|&b| b == 0xFF), "sector 0 (the vector table) untouched");
}

/// The watchdog outlasts the slowest erase (0.5 s at x32) at the LSI's fastest, with the
/// tick after it (which feeds it) to spare; at x8 (0.8 s) it would not.
#[test]
fn the_watchdog_outlasts_the_slowest_erase_across_the_lsi_range() {
    let shortest = iwdg_timeout_s(LSI_MAX_HZ);
    let longest = iwdg_timeout_s(LSI_MIN_HZ);
    assert!((shortest - 0.681).abs() < 0.001 && (longest - 1.882).abs() < 0.001, "{shortest} .. {longest} s");
    assert!(ERASE_16K_MAX_S + 0.001 < shortest, "an erase stalls {ERASE_16K_MAX_S} s, the watchdog fires after {shortest} s");
    assert!(0.8 > shortest, "the x8 erase's 0.8 s would not fit");
}
