//! The console target: arbitrary bytes through the application on the simulated board, with
//! control ticks interleaved.
//!
//! Input: bytes go to `App::input_byte` as they are, except [`TICK`] `n`: `n` control ticks
//! (at most [`MAX_TICKS`] per input), and [`HOLD`]: the bytes up to the next `HOLD` or `TICK`
//! only reach the RX part (`App::receive`), as while a slow command runs, and their lines
//! queue; the command side runs them then (`App::run_commands`). At the end a line ending
//! flushes the last line and blank input lines end any `wait`.
//!
//! Terminal escape sequences (arrow keys) are no part of a line ([`crate::Escapes`]).
//!
//! Invariants (docs/console.md, the safety rules):
//! - one final reply (`ok ...` / `err <code>: ...`) per non-blank line, none for a blank one;
//! - no panic;
//! - no NaN or infinity in an `ok` reply;
//! - no HV target, value or duty at or past the ceiling in force (duty: past the ceiling's duty);
//! - `stop` leaves every duty at 0 and the enable low at once and after the next tick;
//! - `stop` drops the lines queued ahead of it: each answered `err stopped`, in their place,
//!   none run (the board is still stopped when the command side comes to them);
//! - the model-only commands (`solve`, `shape`, `contact`) answer what a board that saw only
//!   the same parameter changes (`param`, `preset`, `cal`, `factory`) answers.
//!
//! What it is not: the QEMU image's console (host-tests/tests/qemu_console.rs).

use finger_fw::control::hv_duty_cap;
use finger_fw::sim::SimBoard;
use finger_fw::{App, CHANNELS};

/// The tick marker: the next byte is a number of ticks.
pub const TICK: u8 = 0xFF;
/// The hold marker: the command side does not run until the next one (or a tick).
pub const HOLD: u8 = 0xFE;
/// Most control ticks one input runs.
pub const MAX_TICKS: u32 = 20_000;
/// The console's receive buffer (docs/console.md "Lines") (the firmware's `console::LINE_MAX`): a longer line is `too-long`.
const LINE_MAX: usize = finger_fw::console::LINE_MAX;

/// The console's lines as docs/console.md defines them: CR, LF or CRLF end a line (CRLF once).
#[derive(Default)]
struct Lines {
    text: Vec<u8>,
    last_cr: bool,
    esc: crate::Escapes,
}

impl Lines {
    /// Feed a byte; the finished line when it ends one.
    fn push(&mut self, b: u8) -> Option<Vec<u8>> {
        if !self.esc.content(b) {
            return None;
        }
        let was_cr = self.last_cr;
        self.last_cr = b == b'\r';
        if b == b'\n' && was_cr {
            return None;
        }
        if b == b'\r' || b == b'\n' {
            return Some(std::mem::take(&mut self.text));
        }
        self.text.push(b);
        None
    }
}

/// Replies a line gets: none for a blank line (spaces and tabs only, within the buffer), one
/// for any other.
fn replies_due(line: &[u8]) -> usize {
    if line.len() <= LINE_MAX && line.iter().all(|&c| c == b' ' || c == b'\t') {
        0
    } else {
        1
    }
}

fn first_word(line: &[u8]) -> Vec<u8> {
    line.split(|&c| c == b' ' || c == b'\t').find(|w| !w.is_empty()).unwrap_or(b"").to_ascii_lowercase()
}

/// A final reply line, as the console protocol crate reads it (`ok ...` / `err <code>: ...`).
fn is_final(l: &str) -> bool {
    finger_protocol::Reply::parse(l).is_ok()
}

/// An `ok` reply carries no NaN or infinity in any value.
fn check_reply_values(text: &str) {
    for l in text.lines().filter(|l| l.starts_with("ok")) {
        // every declared field reads as its kind (protocol/src/field.rs)
        if let Ok(finger_protocol::Reply::Ok(f)) = finger_protocol::Reply::parse(l) {
            assert_eq!(f.check(), Ok(()), "a field of {l:?} does not read as its kind");
        }
        for v in l.split([' ', '=', ',']) {
            let v = v.to_ascii_lowercase();
            let v = v.trim_start_matches(['+', '-']);
            assert!(v != "nan" && v != "inf" && v != "infinity", "non-finite value in {l:?}");
        }
    }
}

/// The HV outputs against the ceiling in force.
fn check_outputs(app: &App<SimBoard>) {
    let vmax = app.vmax();
    let duty_ceiling = app.duty_ceiling();
    let targets = app.targets();
    let volts = app.volts();
    let duties = app.duties();
    let hv = app.board().hv;
    for ch in 0..CHANNELS {
        let cap = hv_duty_cap(hv[ch].max);
        assert!(targets[ch] == 0.0 || (targets[ch] > 0.0 && targets[ch] < vmax[ch]), "channel {ch}: target {} V, ceiling {} V", targets[ch], vmax[ch]);
        assert!(volts[ch] == 0.0 || (volts[ch] > 0.0 && volts[ch] < vmax[ch]), "channel {ch}: value {} V, ceiling {} V", volts[ch], vmax[ch]);
        assert!(
            hv[ch].duty <= duty_ceiling[ch] && hv[ch].duty <= cap,
            "channel {ch}: duty {} past the ceiling's {} (cap {cap})",
            hv[ch].duty,
            duty_ceiling[ch]
        );
        assert_eq!(duties[ch], hv[ch].duty, "channel {ch}: the core's duty is not the PWM's");
    }
}

fn check_stopped(app: &App<SimBoard>, when: &str) {
    let b = app.board();
    assert!(b.hv.iter().all(|h| h.duty == 0) && !b.enable.high, "{when}: duties {:?}, enable {}", b.hv.map(|h| h.duty), b.enable.high);
}

/// A board that sees only the parameter changes: the model-only commands' reference.
struct Reference {
    app: App<SimBoard>,
}

impl Reference {
    fn run(&mut self, line: &[u8]) -> String {
        let mut out = String::new();
        self.app.input(line, &mut out);
        self.app.input(b"\n", &mut out);
        out
    }
}

/// The finals of `text` (`ok ...`/`err ...` lines), each with the lines before it.
fn chunks(text: &str) -> Vec<String> {
    let mut v = Vec::new();
    let mut cur = String::new();
    for l in text.lines() {
        cur.push_str(l);
        cur.push('\n');
        if is_final(l) {
            v.push(std::mem::take(&mut cur));
        }
    }
    v
}

/// The final and `err stopped` replies in the output so far, counted once per line as the
/// output grows (re-reading the whole output at every line made the checker quadratic).
#[derive(Default)]
struct Tally {
    /// Bytes of the output whose lines are counted (up to a line end).
    scanned: usize,
    finals: usize,
    stopped: usize,
}

impl Tally {
    fn line(l: &str) -> (usize, usize) {
        (is_final(l) as usize, l.starts_with("err stopped: ") as usize)
    }

    /// The counts over all of `out` (`str::lines`' lines: an unended last line counts too).
    fn counts(&mut self, out: &str) -> (usize, usize) {
        if let Some(end) = out[self.scanned..].rfind('\n') {
            let end = self.scanned + end + 1;
            for l in out[self.scanned..end].lines() {
                let (f, s) = Tally::line(l);
                self.finals += f;
                self.stopped += s;
            }
            self.scanned = end;
        }
        let (f, s) = out[self.scanned..].lines().map(Tally::line).fold((0, 0), |a, b| (a.0 + b.0, a.1 + b.1));
        (self.finals + f, self.stopped + s)
    }
}

/// The checker's state across one input.
struct Run {
    app: App<SimBoard>,
    reference: Reference,
    out: String,
    lines: Lines,
    /// Final replies due so far.
    due: usize,
    /// `err stopped` replies due so far.
    stopped_due: usize,
    /// The command side is held: lines queue.
    held: bool,
    /// Lines queued while held (after the last stop), in order.
    queued: Vec<Vec<u8>>,
    /// Lines dropped by stops while held, answered when the command side runs.
    dropped: usize,
    /// A stop came while held, and no line after it.
    stop_last: bool,
    tally: Tally,
}

impl Run {
    fn finals(&mut self) -> usize {
        self.tally.counts(&self.out).0
    }

    fn check_counts(&mut self, when: &str) {
        let (finals, stopped) = self.tally.counts(&self.out);
        if !self.app.busy() {
            assert_eq!(finals, self.due, "replies {when}:\n{}", self.out);
        }
        assert_eq!(stopped, self.stopped_due, "`err stopped` replies {when}:\n{}", self.out);
    }

    /// A model-only line's reply against the reference board's; a parameter change that took
    /// to the reference board too.
    fn against_reference(&mut self, line: &[u8], reply: &str) {
        if line.len() > LINE_MAX {
            return;
        }
        match &first_word(line)[..] {
            b"solve" | b"shape" | b"contact" => {
                let want = self.reference.run(line);
                assert_eq!(reply, want, "model-only {:?} differs from the reference board's", String::from_utf8_lossy(line));
            }
            // `factory` too: the defaults back (the checker once left the reference board at
            // the parameters before it: `regressions/console/factory-then-contact`)
            b"param" | b"preset" | b"cal" | b"factory" if reply.starts_with("ok") => {
                let want = self.reference.run(line);
                assert_eq!(reply, want, "{:?} on the reference board", String::from_utf8_lossy(line));
            }
            _ => {}
        }
    }

    fn feed(&mut self, b: u8) {
        let was_busy = self.app.busy();
        let start = self.out.len();
        if self.held {
            self.app.receive(b, &mut self.out);
        } else {
            self.app.input_byte(b, &mut self.out);
        }
        let new = self.out[start..].to_string();
        check_reply_values(&new);
        check_outputs(&self.app);
        let stopped_now = new.lines().any(|l| l == "ok stopped");
        if stopped_now {
            check_stopped(&self.app, "at stop");
            if !self.held {
                self.app.tick(1, &mut self.out);
                check_stopped(&self.app, "one tick after stop");
            }
        }
        let Some(line) = self.lines.push(b) else {
            assert!(!stopped_now, "`ok stopped` inside a line");
            return;
        };
        assert_eq!(stopped_now, first_word(&line) == b"stop", "stop for {:?}", String::from_utf8_lossy(&line));
        let due = replies_due(&line);
        self.due += due;
        if self.held {
            if stopped_now {
                // every line queued ahead of the stop is dropped, answered `err stopped`
                self.dropped += self.queued.len();
                self.stopped_due += self.queued.len();
                self.queued.clear();
                self.stop_last = true;
            } else if due > 0 {
                self.queued.push(line);
                self.stop_last = false;
            }
            return;
        }
        self.check_counts(&format!("after line {:?}", String::from_utf8_lossy(&line)));
        // the reply to this line alone: no wait ran before it, none runs now
        if !was_busy && !self.app.busy() {
            self.against_reference(&line, &new);
        }
    }

    /// The command side runs what queued while held.
    fn release(&mut self) {
        if !self.held {
            return;
        }
        self.held = false;
        let was_busy = self.app.busy();
        let start = self.out.len();
        self.app.run_commands(&mut self.out);
        let new = self.out[start..].to_string();
        check_reply_values(&new);
        check_outputs(&self.app);
        let mut ch = chunks(&new);
        // a `wait` that ran while held ends first (input came), with its own reply
        if was_busy && !ch.is_empty() {
            let w = ch.remove(0);
            assert!(w.starts_with("ok waited="), "the held wait's reply: {w:?}");
        }
        let dropped = std::mem::take(&mut self.dropped);
        for (k, c) in ch.iter().take(dropped).enumerate() {
            assert!(c.starts_with("err stopped: ") && c.lines().count() == 1, "dropped line {k}'s reply: {c:?}\n{}", self.out);
        }
        if std::mem::take(&mut self.stop_last) {
            check_stopped(&self.app, "after the lines a stop dropped");
            assert!(!self.app.armed(), "armed after the lines a stop dropped");
        }
        let queued = std::mem::take(&mut self.queued);
        for (line, c) in queued.iter().zip(ch.iter().skip(dropped)) {
            assert!(!c.starts_with("err stopped: "), "{:?} dropped, no stop after it", String::from_utf8_lossy(line));
            self.against_reference(line, c);
        }
        self.check_counts("after the held lines ran");
    }
}

/// Runs one input; panics when an invariant breaks.
pub fn check(data: &[u8]) {
    let mut r = Run {
        app: App::new(SimBoard::default()),
        reference: Reference { app: App::new(SimBoard::default()) },
        out: String::new(),
        lines: Lines::default(),
        due: 0,
        stopped_due: 0,
        held: false,
        queued: Vec::new(),
        dropped: 0,
        stop_last: false,
        tally: Tally::default(),
    };
    // the board without its weight (both boards, before the input; the reply is not the
    // input's): this target's corpus was built on the finger without it, and the coupled solves
    // under gravity cost it 14 times the time; gravity at the console is gravity_console's
    for app in [&mut r.app, &mut r.reference.app] {
        let mut s = String::new();
        app.input(b"param grav 0\n", &mut s);
        assert!(s.starts_with("ok grav=0"), "the board without its weight: {s}");
    }
    let mut ticks = 0u32;
    let mut i = 0;
    while i < data.len() {
        let b = data[i];
        i += 1;
        if b == HOLD {
            if r.held {
                r.release();
            } else {
                r.held = true;
            }
            continue;
        }
        if b == TICK {
            r.release();
            let n = (data.get(i).copied().unwrap_or(1) as u32).min(MAX_TICKS - ticks);
            i += 1;
            for _ in 0..n {
                r.app.tick(1, &mut r.out);
                check_outputs(&r.app);
            }
            ticks += n;
            continue;
        }
        r.feed(b);
    }
    r.feed(b'\n');
    r.release();
    // blank lines end the `wait`s still running (input ends a wait early)
    let mut guard = 0;
    while r.app.busy() {
        r.feed(b' ');
        r.feed(b'\n');
        guard += 1;
        assert!(guard < 10_000, "a wait never ends");
    }
    let finals = r.finals();
    assert_eq!(finals, r.due, "replies at the end:\n{}", r.out);
    r.check_counts("at the end");
}
