//! The rx target: the UART byte stream with overruns at arbitrary points into the RX
//! interrupt's line handling (`finger_fw::rx::RxLines`), records taken at arbitrary points.
//!
//! Input: each byte goes to `RxLines::push`, except [`OVERRUN`] (the UART lost bytes here:
//! `RxLines::overrun`) and [`POP`] (the command side takes every queued record).
//!
//! Invariants: each line sent comes out whole and alone (lowercased, in order) or as one
//! `err overrun` count, never mixed with another; a line with an overrun in it never comes out;
//! an unbroken line is lost only when the ring is full; an overlong line is one `too-long`;
//! blank lines give nothing; a `stop` line is `RxEvent::Stop` at its end (unless a byte of its
//! first word was lost) and never queued; a `stop` drops every line queued ahead of it (not yet
//! taken): they come out as one `err stopped` count, in their place, whatever they were.
//!
//! What it is not: the command side (the console target).

use finger_fw::console::LINE_MAX;
use finger_fw::rx::{Record, RxEvent, RxLines, OVERRUN_RECORD, RX_RING};
use std::collections::VecDeque;

pub const OVERRUN: u8 = 0xFE;
pub const POP: u8 = 0xFD;

/// What a sent line must give.
#[derive(Debug, Clone, PartialEq)]
enum Want {
    Line(Vec<u8>),
    TooLong,
    /// An overrun hit it: only `err overrun`.
    Lost,
    /// Sent whole while the ring was nearly full: as sent, or lost.
    OrLost(Box<Want>),
    /// Queued when a `stop` came: only `err stopped`.
    Stopped,
}

impl Want {
    /// Ring bytes its record takes.
    fn ring_bytes(&self) -> usize {
        match self {
            Want::Line(v) => v.len() + 2,
            Want::OrLost(w) => w.ring_bytes(),
            Want::TooLong => 2,
            Want::Lost => OVERRUN_RECORD,
            // the stopped lines share one record (counted once, below)
            Want::Stopped => 0,
        }
    }
}

/// The line being sent, as the contract sees it.
#[derive(Default)]
struct Sending {
    text: Vec<u8>,
    last_cr: bool,
    /// An overrun came during the line.
    broken: bool,
    /// An overrun came before the first word ended (a space or tab after it).
    word_broken: bool,
}

impl Sending {
    fn first_word_ended(&self) -> bool {
        let t = &self.text;
        let start = t.iter().position(|&c| c != b' ' && c != b'\t');
        start.is_some_and(|s| t[s..].iter().any(|&c| c == b' ' || c == b'\t'))
    }
    fn first_word_is_stop(&self) -> bool {
        let w = self.text.split(|&c| c == b' ' || c == b'\t').find(|w| !w.is_empty()).unwrap_or(b"");
        w.eq_ignore_ascii_case(b"stop")
    }
}

/// Runs one input; panics when an invariant breaks.
pub fn check(data: &[u8]) {
    let mut rx = RxLines::new();
    let mut s = Sending::default();
    // records due, oldest first, and the ring bytes they take
    let mut queued: VecDeque<Want> = VecDeque::new();
    let mut popped = 0usize;
    let mut esc = crate::Escapes::default();
    let take = |rx: &mut RxLines, queued: &mut VecDeque<Want>, popped: &mut usize| {
        while let Some(rec) = rx.pop() {
            match rec {
                Record::Line(v) => {
                    let w = queued.pop_front().unwrap_or_else(|| panic!("line {:?} never sent (record {popped})", String::from_utf8_lossy(&v)));
                    let w = if let Want::OrLost(w) = w { *w } else { w };
                    assert_eq!(w, Want::Line(v.to_vec()), "record {popped}: a line not as sent");
                    *popped += 1;
                }
                Record::TooLong => {
                    let w = queued.pop_front().expect("too-long record for no line");
                    let w = if let Want::OrLost(w) = w { *w } else { w };
                    assert_eq!(w, Want::TooLong, "record {popped}");
                    *popped += 1;
                }
                Record::Overrun(n) => {
                    assert!(n > 0, "an overrun record of 0 lines");
                    for _ in 0..n {
                        let w = queued.pop_front().expect("more lines lost than sent");
                        assert!(matches!(w, Want::Lost | Want::OrLost(_)), "record {popped}: {w:?} reported lost");
                        *popped += 1;
                    }
                }
                Record::Stopped(n) => {
                    assert!(n > 0, "a stopped record of 0 lines");
                    for _ in 0..n {
                        let w = queued.pop_front().expect("more lines stopped than sent");
                        assert_eq!(w, Want::Stopped, "record {popped}: reported stopped");
                        *popped += 1;
                    }
                }
            }
        }
        assert!(queued.is_empty(), "lines sent but never given: {queued:?}");
    };
    for &b in data {
        match b {
            OVERRUN => {
                rx.overrun();
                s.broken = true;
                if !s.first_word_ended() {
                    s.word_broken = true;
                }
                continue;
            }
            POP => {
                take(&mut rx, &mut queued, &mut popped);
                continue;
            }
            _ => {}
        }
        let ev = rx.push(b);
        if !esc.content(b) {
            assert_eq!(ev, RxEvent::Nothing, "an event inside an escape sequence");
            continue;
        }
        let was_cr = s.last_cr;
        s.last_cr = b == b'\r';
        let ends = (b == b'\r' || b == b'\n') && !(b == b'\n' && was_cr);
        if !ends {
            if b != b'\r' && b != b'\n' {
                s.text.push(b);
            }
            assert_eq!(ev, RxEvent::Nothing, "an event inside a line");
            continue;
        }
        let line = std::mem::take(&mut s);
        s.last_cr = line.last_cr; // a CRLF spans two lines' bookkeeping
        let stop = line.first_word_is_stop() && !line.word_broken;
        assert_eq!(ev == RxEvent::Stop, stop, "stop event for {:?} (overrun {})", String::from_utf8_lossy(&line.text), line.broken);
        if stop {
            // every line not yet taken is dropped
            for w in queued.iter_mut() {
                *w = Want::Stopped;
            }
            continue;
        }
        let blank = line.text.iter().all(|&c| c == b' ' || c == b'\t');
        let want = if line.broken {
            Want::Lost
        } else if line.text.len() > LINE_MAX {
            Want::TooLong
        } else if blank {
            continue;
        } else {
            Want::Line(line.text.to_ascii_lowercase())
        };
        // an unbroken line is lost only when the ring cannot take it: the records queued
        // ahead (each overrun counted as its own record: an upper bound) leave too little room
        let stopped = queued.iter().any(|w| *w == Want::Stopped);
        let ahead: usize = queued.iter().map(Want::ring_bytes).sum::<usize>() + if stopped { OVERRUN_RECORD } else { 0 };
        let room = ahead + want.ring_bytes() + OVERRUN_RECORD <= RX_RING;
        queued.push_back(if want == Want::Lost || room { want } else { Want::OrLost(Box::new(want)) });
    }
    take(&mut rx, &mut queued, &mut popped);
}
