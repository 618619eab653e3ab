//! Console input at interrupt level: bytes into lines, `stop` spotted, lines queued.
//!
//! What it is: what the UART RX interrupt runs for each byte (the host's `App::input_byte`
//! runs the same). [`LineBuf`] assembles the line; at its end a line whose first word is
//! `stop` (any case, any arguments) is returned as [`RxEvent::Stop`] for the caller to act on
//! at once and is not queued; any other line goes into a bounded ring ([`RX_RING`] bytes,
//! `heapless::Deque`) as a record the command side pops ([`RxLines::pop`]).
//! A line lost to an overrun (a byte the UART dropped, [`RxLines::overrun`], or no room left
//! in the ring) is discarded whole and queued as [`Record::Overrun`], answered `err overrun`.
//! A `stop` flushes the ring: every line queued before it (not yet popped) is dropped, and the
//! ring keeps one [`Record::Stopped`] with their count, answered `err stopped` once per line.
//!
//! What it is not: the command parser (`crate::app`).

use heapless::{Deque, Vec};

use crate::console::{EscFilter, Line, LineBuf, LINE_MAX};

/// Bytes of queued lines (each line takes its length + 2); smaller on the Cortex-M3 image
/// (20 KiB of RAM).
#[cfg(not(m3))]
pub const RX_RING: usize = 4096;
#[cfg(m3)]
pub const RX_RING: usize = 1024;

const KIND_LINE: u8 = 1;
const KIND_TOO_LONG: u8 = 2;
const KIND_OVERRUN: u8 = 3;
const KIND_STOPPED: u8 = 4;
/// Ring bytes of an overrun record (its kind and a u32 count, so that every lost line keeps
/// its reply); kept free behind every other record. A stopped record is the same size.
pub const OVERRUN_RECORD: usize = 5;

/// What a byte did.
#[derive(Debug, PartialEq, Eq, Clone, Copy)]
pub enum RxEvent {
    Nothing,
    /// A `stop` line ended: act now, reply `ok stopped`.
    Stop,
}

/// A queued line, as the command side gets it.
#[derive(Debug, PartialEq, Eq)]
pub enum Record {
    /// A complete line (lowercased, without its terminator).
    Line(Vec<u8, LINE_MAX>),
    /// A line longer than LINE_MAX, discarded.
    TooLong,
    /// `n` lines lost to overruns.
    Overrun(u32),
    /// `n` lines received before a `stop` and dropped by it, in the ring's place of the first.
    Stopped(u32),
}

/// The first word of the line being received, for `stop`.
#[derive(Default)]
struct FirstWord {
    buf: [u8; 5],
    len: u8,
    /// The word ended (a space or tab after it).
    done: bool,
    /// A byte of it was lost.
    broken: bool,
}

impl FirstWord {
    fn push(&mut self, b: u8) {
        if self.done || self.broken {
            return;
        }
        if b == b' ' || b == b'\t' {
            self.done = self.len > 0;
            return;
        }
        if (self.len as usize) < self.buf.len() {
            self.buf[self.len as usize] = b.to_ascii_lowercase();
        }
        self.len = self.len.saturating_add(1);
    }
    fn is_stop(&self) -> bool {
        !self.broken && self.len == 4 && &self.buf[..4] == b"stop"
    }
}

/// Line assembly, `stop` and the ring of queued lines.
pub struct RxLines {
    esc: EscFilter,
    line: LineBuf,
    word: FirstWord,
    /// Bytes of the current line were lost: discard it at its end.
    broken: bool,
    ring: Deque<u8, RX_RING>,
    /// The ring's last record is an overrun record (its count may grow).
    overrun_open: bool,
    /// Lines the ring's records stand for (an overrun or stopped record: its count).
    queued: u32,
    /// A byte arrived since the last [`RxLines::pop`].
    seen: bool,
    /// Bytes received (for tests and the report).
    pub received: u32,
}

impl Default for RxLines {
    fn default() -> Self {
        Self::new()
    }
}

impl RxLines {
    pub const fn new() -> Self {
        RxLines {
            esc: EscFilter::new(),
            line: LineBuf::new(),
            word: FirstWord { buf: [0; 5], len: 0, done: false, broken: false },
            broken: false,
            ring: Deque::new(),
            overrun_open: false,
            queued: 0,
            seen: false,
            received: 0,
        }
    }

    /// One received byte.
    pub fn push(&mut self, b: u8) -> RxEvent {
        self.received = self.received.wrapping_add(1);
        // arrow and function keys: no part of a line, no reply
        if !self.esc.pass(b) {
            return RxEvent::Nothing;
        }
        // input that ends a `wait`: any byte but a line ending (the LF of a `wait`'s own CRLF
        // arrives after its line)
        if b != b'\r' && b != b'\n' {
            self.seen = true;
        }
        let end = match self.line.push(b) {
            None => {
                if b != b'\n' && b != b'\r' {
                    self.word.push(b);
                }
                return RxEvent::Nothing;
            }
            Some(Line::TooLong) => None,
            Some(Line::Text(t)) => {
                let mut v: Vec<u8, LINE_MAX> = Vec::new();
                let _ = v.extend_from_slice(t);
                Some(v)
            }
        };
        let stop = self.word.is_stop() && (self.word.done || !self.broken);
        let broken = self.broken;
        self.word = FirstWord::default();
        self.broken = false;
        if stop {
            self.flush();
            return RxEvent::Stop;
        }
        if broken {
            self.record_overrun();
            return RxEvent::Nothing;
        }
        match end {
            None => self.record(KIND_TOO_LONG, &[]),
            Some(v) if v.iter().all(|&c| c == b' ' || c == b'\t') => {} // blank: no reply
            Some(v) => self.record(KIND_LINE, &v),
        }
        RxEvent::Nothing
    }

    /// The UART lost bytes (overrun): the line being received is discarded at its end.
    pub fn overrun(&mut self) {
        self.broken = true;
        if !self.word.done {
            self.word.broken = true;
        }
    }

    fn record(&mut self, kind: u8, bytes: &[u8]) {
        if self.ring.capacity() - self.ring.len() < bytes.len() + 2 + OVERRUN_RECORD {
            self.record_overrun();
            return;
        }
        let _ = self.ring.push_back(kind);
        let _ = self.ring.push_back(bytes.len() as u8);
        for &b in bytes {
            let _ = self.ring.push_back(b);
        }
        self.overrun_open = false;
        self.queued = self.queued.saturating_add(1);
    }

    /// A `stop` ended: every queued record becomes one stopped record of all their lines
    /// (constant time: the ring's bytes are not read).
    fn flush(&mut self) {
        self.ring.clear();
        self.overrun_open = false;
        if self.queued > 0 {
            let _ = self.ring.push_back(KIND_STOPPED);
            for b in self.queued.to_le_bytes() {
                let _ = self.ring.push_back(b);
            }
        }
    }

    fn record_overrun(&mut self) {
        let mut n = 0u32;
        if self.overrun_open {
            let mut le = [0u8; 4];
            for b in le.iter_mut().rev() {
                *b = self.ring.pop_back().unwrap_or(0);
            }
            n = u32::from_le_bytes(le);
        } else if self.ring.capacity() - self.ring.len() < OVERRUN_RECORD || self.ring.push_back(KIND_OVERRUN).is_err() {
            return;
        }
        for b in n.saturating_add(1).to_le_bytes() {
            let _ = self.ring.push_back(b);
        }
        self.overrun_open = true;
        self.queued = self.queued.saturating_add(1);
    }

    /// Lines are waiting.
    pub fn pending(&self) -> bool {
        !self.ring.is_empty()
    }

    /// A byte arrived since the last record was taken, or a record is waiting (what ends a
    /// `wait` early). Clears the byte flag.
    pub fn take_input_seen(&mut self) -> bool {
        core::mem::take(&mut self.seen) || self.pending()
    }

    /// The oldest queued line.
    pub fn pop(&mut self) -> Option<Record> {
        let kind = self.ring.pop_front()?;
        self.seen = false;
        if kind == KIND_OVERRUN || kind == KIND_STOPPED {
            let mut le = [0u8; 4];
            for b in le.iter_mut() {
                *b = self.ring.pop_front().unwrap_or(0);
            }
            // the open overrun record is the ring's last
            if self.ring.is_empty() {
                self.overrun_open = false;
            }
            let n = u32::from_le_bytes(le);
            self.queued = self.queued.saturating_sub(n);
            return Some(if kind == KIND_STOPPED { Record::Stopped(n) } else { Record::Overrun(n) });
        }
        self.queued = self.queued.saturating_sub(1);
        let n = self.ring.pop_front().unwrap_or(0);
        Some(match kind {
            KIND_LINE => {
                let mut v = Vec::new();
                for _ in 0..n {
                    if let Some(b) = self.ring.pop_front() {
                        let _ = v.push(b);
                    }
                }
                Record::Line(v)
            }
            _ => Record::TooLong,
        })
    }
}
