//! The stored settings: the record's format and the store it lives in.
//!
//! What it is: the bytes of one settings record ([`Record`]: a format version, a save counter,
//! the preset, and every console-settable value keyed by its name, closed by a CRC-32) and
//! [`FlashStore`], which keeps the newest record in `sequential-storage`'s map over two or more
//! erase pages of any `NorFlash` (the chip's flash sectors on the board, a RAM region in QEMU,
//! a mock on the host). A power cut in the middle of a save leaves the map with the old record
//! or the new one (the crate writes an item and its own CRC, then reads past a torn one).
//!
//! What it is not: what the values mean. Which values are stored, their ranges and the
//! ceiling check are the command side's (`app::config`), which reads a record as a console
//! `param` would and refuses a store that fails any check whole. Board constants are not
//! console-settable, so they are never in a record.
//!
//! Format (little endian): `FCFG`, version u16, value count u16, save counter u32, preset u8,
//! 3 zero bytes, then per value a tag u16 (CRC-16 of its name, [`tag`]) and an f32, then the
//! CRC-32 (ISO-HDLC) of everything before it. Values keyed by name: a later build reads an
//! older record's names it still has, keeps its compiled default for names the record lacks,
//! and refuses a record holding a name it does not know. A record of another version is refused.

use crc::{Crc, NoTable, CRC_16_IBM_3740, CRC_32_ISO_HDLC};
use embassy_futures::block_on;
use embedded_storage_async::nor_flash::{ErrorType, NorFlash, NorFlashError, NorFlashErrorKind, ReadNorFlash};
use heapless::Vec;
use sequential_storage::cache::{Cache, Uncached};
use sequential_storage::map::{MapConfig, MapStorage};

/// The record format this build writes and reads.
pub const FORMAT_VERSION: u16 = 1;
const MAGIC: [u8; 4] = *b"FCFG";
const HEADER: usize = 16;
/// Most values a record holds.
pub const MAX_VALUES: usize = 48;
/// Longest record, bytes.
pub const RECORD_MAX: usize = HEADER + 6 * MAX_VALUES + 4;

const CRC32: Crc<u32, NoTable> = Crc::<u32, NoTable>::new(&CRC_32_ISO_HDLC);
const CRC16: Crc<u16, NoTable> = Crc::<u16, NoTable>::new(&CRC_16_IBM_3740);

/// A value's key in the record: the CRC-16 of `group` and `name` (`p` model parameters, `c`
/// calibration factors, `f` firmware parameters).
pub fn tag(group: u8, name: &str) -> u16 {
    let mut d = CRC16.digest();
    d.update(&[group, b':']);
    d.update(name.as_bytes());
    d.finalize()
}

/// One settings record, decoded: nothing in it is checked beyond its bytes.
#[derive(Clone, Debug, PartialEq)]
pub struct Record {
    /// Saves so far, this one included.
    pub counter: u32,
    /// The preset the parameters started from (0 default, 1 paper).
    pub preset: u8,
    /// (tag, value) in the order written.
    pub values: Vec<(u16, f32), MAX_VALUES>,
}

/// Why stored bytes are not a record of this build.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum FormatError {
    /// Shorter than a header, or its length disagrees with its value count.
    Length,
    /// Not a settings record.
    Magic,
    /// Written by another format version (refused, never read).
    Version(u16),
    /// The CRC-32 does not match the bytes.
    Checksum,
}

impl Record {
    /// The record's bytes into `out`; their length.
    pub fn encode(&self, out: &mut [u8; RECORD_MAX]) -> usize {
        out[..4].copy_from_slice(&MAGIC);
        out[4..6].copy_from_slice(&FORMAT_VERSION.to_le_bytes());
        out[6..8].copy_from_slice(&(self.values.len() as u16).to_le_bytes());
        out[8..12].copy_from_slice(&self.counter.to_le_bytes());
        out[12..16].copy_from_slice(&[self.preset, 0, 0, 0]);
        let mut n = HEADER;
        for &(t, v) in &self.values {
            out[n..n + 2].copy_from_slice(&t.to_le_bytes());
            out[n + 2..n + 6].copy_from_slice(&v.to_le_bytes());
            n += 6;
        }
        let crc = CRC32.checksum(&out[..n]);
        out[n..n + 4].copy_from_slice(&crc.to_le_bytes());
        n + 4
    }

    /// A record from its bytes: magic, version, length and checksum checked, in that order.
    pub fn decode(b: &[u8]) -> Result<Record, FormatError> {
        if b.len() < HEADER + 4 {
            return Err(FormatError::Length);
        }
        if b[..4] != MAGIC {
            return Err(FormatError::Magic);
        }
        let u16_at = |i: usize| u16::from_le_bytes([b[i], b[i + 1]]);
        let u32_at = |i: usize| u32::from_le_bytes([b[i], b[i + 1], b[i + 2], b[i + 3]]);
        let version = u16_at(4);
        if version != FORMAT_VERSION {
            return Err(FormatError::Version(version));
        }
        let count = u16_at(6) as usize;
        if count > MAX_VALUES || b.len() != HEADER + 6 * count + 4 {
            return Err(FormatError::Length);
        }
        let end = HEADER + 6 * count;
        if CRC32.checksum(&b[..end]) != u32_at(end) || b[13..16] != [0, 0, 0] {
            return Err(FormatError::Checksum);
        }
        let mut values = Vec::new();
        for k in 0..count {
            let i = HEADER + 6 * k;
            let _ = values.push((u16_at(i), f32::from_bits(u32_at(i + 2))));
        }
        Ok(Record { counter: u32_at(8), preset: b[12], values })
    }
}

/// A storage failure (the flash, or the crate's own checks of its pages).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum StoreError {
    /// The flash refused an operation (or, on the host's mock, the power went).
    Flash,
    /// The pages hold something the map cannot read back (erase to recover: `factory`).
    Corrupted,
    /// Anything else the crate reports (full, buffer, a logic error).
    Other,
    /// The pages need a repair (an erase or a write), which a read that may not write
    /// ([`ConfigStore::peek`]) refused.
    Repair,
}

impl StoreError {
    pub fn name(self) -> &'static str {
        match self {
            StoreError::Flash => "flash",
            StoreError::Corrupted => "corrupted",
            StoreError::Other => "store",
            StoreError::Repair => "repair",
        }
    }
}

/// Where the command side keeps its record: read the newest, write a new one, erase all.
pub trait ConfigStore {
    /// The newest record's bytes into `buf`: their length, or None when nothing is stored.
    fn read(&mut self, buf: &mut [u8; RECORD_MAX]) -> Result<Option<usize>, StoreError>;
    /// As `read`, but writing nothing: where `read` would repair, [`StoreError::Repair`]
    /// (an erase stalls every fetch from flash, the trip handler's included: `config` while
    /// armed reads this way).
    fn peek(&mut self, buf: &mut [u8; RECORD_MAX]) -> Result<Option<usize>, StoreError>;
    /// Store `record` as the newest.
    fn write(&mut self, record: &[u8]) -> Result<(), StoreError>;
    /// Erase every page: nothing stored.
    fn erase(&mut self) -> Result<(), StoreError>;
}

/// The map's key of the settings record (the only item).
const KEY: u8 = 1;
/// The map's work buffer: key and the longest record, word-aligned.
const BUF: usize = (1 + RECORD_MAX).div_ceil(32) * 32;

/// A flash that counts its erases and writes: a read that wrote is the map repairing what it
/// found ([`FlashStore::read`]); the counts are the wear figures (docs/firmware.md).
pub struct Counted<S> {
    flash: S,
    /// Pages erased, writes made, bytes written.
    pub erases: u32,
    pub writes: u32,
    pub bytes_written: u32,
    /// Erases and writes refused ([`ConfigStore::peek`]).
    refuse: bool,
}

impl<S> Counted<S> {
    /// The flash itself.
    pub fn flash_mut(&mut self) -> &mut S {
        &mut self.flash
    }
}

/// The flash's error, or an erase or write refused while the store may not write.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CountedError<E> {
    Flash(E),
    Refused,
}

impl<E: NorFlashError> NorFlashError for CountedError<E> {
    fn kind(&self) -> NorFlashErrorKind {
        match self {
            CountedError::Flash(e) => e.kind(),
            CountedError::Refused => NorFlashErrorKind::Other,
        }
    }
}

impl<S: ErrorType> ErrorType for Counted<S> {
    type Error = CountedError<S::Error>;
}

impl<S: ReadNorFlash> ReadNorFlash for Counted<S> {
    const READ_SIZE: usize = S::READ_SIZE;
    async fn read(&mut self, offset: u32, bytes: &mut [u8]) -> Result<(), Self::Error> {
        self.flash.read(offset, bytes).await.map_err(CountedError::Flash)
    }
    fn capacity(&self) -> usize {
        self.flash.capacity()
    }
}

impl<S: NorFlash> NorFlash for Counted<S> {
    const WRITE_SIZE: usize = S::WRITE_SIZE;
    const ERASE_SIZE: usize = S::ERASE_SIZE;
    async fn erase(&mut self, from: u32, to: u32) -> Result<(), Self::Error> {
        if self.refuse {
            return Err(CountedError::Refused);
        }
        self.erases += (to.saturating_sub(from) as usize / S::ERASE_SIZE) as u32;
        self.flash.erase(from, to).await.map_err(CountedError::Flash)
    }
    async fn write(&mut self, offset: u32, bytes: &[u8]) -> Result<(), Self::Error> {
        if self.refuse {
            return Err(CountedError::Refused);
        }
        self.writes += 1;
        self.bytes_written += bytes.len() as u32;
        self.flash.write(offset, bytes).await.map_err(CountedError::Flash)
    }
}

/// The settings record in `sequential-storage`'s map over the pages of `flash`
/// (`range` its byte offsets: whole erase pages, at least two).
pub struct FlashStore<S: NorFlash> {
    map: MapStorage<u8, Counted<S>, Cache<Uncached, Uncached, Uncached, u8>>,
    buf: [u8; BUF],
}

impl<S: NorFlash> FlashStore<S> {
    /// Panics if `range` is not at least two whole erase pages (a build error, not input).
    pub fn new(flash: S, range: core::ops::Range<u32>) -> Self {
        let config = match MapConfig::try_new(range) {
            Ok(c) => c,
            Err(_) => panic!("settings store: at least two whole erase pages"),
        };
        let flash = Counted { flash, erases: 0, writes: 0, bytes_written: 0, refuse: false };
        FlashStore { map: MapStorage::new(flash, config, Cache::new_uncached()), buf: [0; BUF] }
    }

    /// The flash and its counters.
    pub fn flash(&mut self) -> &mut Counted<S> {
        self.map.flash()
    }

    /// Give the flash back.
    pub fn into_flash(self) -> S {
        self.map.destroy().0.flash
    }
}

fn store_err<E>(e: sequential_storage::Error<CountedError<E>>) -> StoreError {
    match e {
        sequential_storage::Error::Storage { value: CountedError::Refused, .. } => StoreError::Repair,
        sequential_storage::Error::Storage { .. } => StoreError::Flash,
        sequential_storage::Error::Corrupted { .. } => StoreError::Corrupted,
        _ => StoreError::Other,
    }
}

impl<S: NorFlash> FlashStore<S> {
    /// Every byte of the pages erased (0xFF).
    fn blank(&mut self) -> Result<bool, StoreError> {
        let range = self.map.flash_range();
        let mut a = range.start;
        while a < range.end {
            let n = (range.end - a).min(BUF as u32);
            let chunk = &mut self.buf[..n as usize];
            block_on(self.map.flash().read(a, chunk)).map_err(|_| StoreError::Flash)?;
            if chunk.iter().any(|&b| b != 0xFF) {
                return Ok(false);
            }
            a += n;
        }
        Ok(true)
    }
}

impl<S: NorFlash> ConfigStore for FlashStore<S> {
    /// The map repairs what it cannot read (re-erases a half-erased page, redoes an
    /// interrupted migration) and reads again. No record, and a repair made or the pages not
    /// blank: the pages held something unreadable, which is `Corrupted`, not an empty store.
    fn read(&mut self, out: &mut [u8; RECORD_MAX]) -> Result<Option<usize>, StoreError> {
        let changes = |f: &Counted<S>| (f.erases, f.writes);
        let before = changes(self.map.flash());
        let item = block_on(self.map.fetch_item::<&[u8]>(&mut self.buf, &KEY)).map_err(store_err)?;
        let found = item.map(|b| {
            // a longer item is not a record of this build: cut, it fails its checks
            let n = b.len().min(RECORD_MAX);
            out[..n].copy_from_slice(&b[..n]);
            n
        });
        let repaired = changes(self.map.flash()) != before;
        if found.is_none() && (repaired || !self.blank()?) {
            return Err(StoreError::Corrupted);
        }
        Ok(found)
    }

    fn peek(&mut self, out: &mut [u8; RECORD_MAX]) -> Result<Option<usize>, StoreError> {
        self.map.flash().refuse = true;
        let r = self.read(out);
        self.map.flash().refuse = false;
        r
    }

    fn write(&mut self, record: &[u8]) -> Result<(), StoreError> {
        block_on(self.map.store_item(&mut self.buf, &KEY, &record)).map_err(store_err)
    }

    fn erase(&mut self) -> Result<(), StoreError> {
        block_on(self.map.erase_all()).map_err(store_err)
    }
}
