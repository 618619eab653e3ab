//! The console target: arbitrary bytes through the application on the simulated board, with
//! control ticks interleaved.
//!
//! Input: bytes go to `App::input_byte` as they are, except [`TICK`] `n`: `n` control ticks
//! (at most [`MAX_TICKS`] per input). At the end a line ending flushes the last line and
//! blank input lines end any `wait`.
//!
//! Terminal escape sequences (arrow keys) are no part of a line ([`crate::Escapes`]).
//!
//! Invariants (docs/console.md, the safety rules):
//! - one final reply (`ok ...` / `err <code>: ...`) per non-blank line, none for a blank one;
//! - no panic;
//! - no NaN or infinity in an `ok` reply;
//! - no HV target, value or duty at or past the ceiling in force (duty: past the ceiling's duty);
//! - `stop` leaves every duty at 0 and the enable low at once and after the next tick;
//! - the model-only commands (`solve`, `shape`, `contact`) answer what a board that saw only
//!   the same parameter changes answers.
//!
//! What it is not: the QEMU image's console (host-tests/tests/qemu_console.rs).

use finger_fw::control::hv_duty_cap;
use finger_fw::sim::SimBoard;
use finger_fw::{App, CHANNELS};

/// The tick marker: the next byte is a number of ticks.
pub const TICK: u8 = 0xFF;
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

fn is_final(l: &str) -> bool {
    l == "ok" || l.starts_with("ok ") || l.starts_with("err ")
}

/// An `ok` reply carries no NaN or infinity in any value.
fn check_reply_values(text: &str) {
    for l in text.lines().filter(|l| l.starts_with("ok")) {
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
        assert!(hv[ch].duty <= duty_ceiling[ch] && hv[ch].duty <= cap, "channel {ch}: duty {} past the ceiling's {} (cap {cap})", hv[ch].duty, duty_ceiling[ch]);
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

/// Runs one input; panics when an invariant breaks.
pub fn check(data: &[u8]) {
    let mut app = App::new(SimBoard::default());
    let mut reference = Reference { app: App::new(SimBoard::default()) };
    let mut out = String::new();
    let mut lines = Lines::default();
    let mut due = 0usize;
    let mut ticks = 0u32;
    let mut i = 0;
    let mut feed = |app: &mut App<SimBoard>, b: u8, out: &mut String, due: &mut usize| {
        let was_busy = app.busy();
        let start = out.len();
        app.input_byte(b, out);
        let new = out[start..].to_string();
        check_reply_values(&new);
        check_outputs(app);
        if new.lines().any(|l| l == "ok stopped") {
            check_stopped(app, "at stop");
            app.tick(1, out);
            check_stopped(app, "one tick after stop");
        }
        if let Some(line) = lines.push(b) {
            *due += replies_due(&line);
            if !app.busy() {
                let finals = out.lines().filter(|l| is_final(l)).count();
                assert_eq!(finals, *due, "replies after line {:?}:\n{out}", String::from_utf8_lossy(&line));
            }
            // the reply to this line alone: no wait ran before it, none runs now
            if !was_busy && !app.busy() && line.len() <= LINE_MAX {
                let word = first_word(&line);
                match &word[..] {
                    b"solve" | b"shape" | b"contact" => {
                        let want = reference.run(&line);
                        assert_eq!(new, want, "model-only {:?} differs from the reference board's", String::from_utf8_lossy(&line));
                    }
                    b"param" | b"preset" | b"cal" if new.starts_with("ok") => {
                        let want = reference.run(&line);
                        assert_eq!(new, want, "{:?} on the reference board", String::from_utf8_lossy(&line));
                    }
                    _ => {}
                }
            }
        }
    };
    while i < data.len() {
        let b = data[i];
        i += 1;
        if b == TICK {
            let n = (data.get(i).copied().unwrap_or(1) as u32).min(MAX_TICKS - ticks);
            i += 1;
            for _ in 0..n {
                app.tick(1, &mut out);
                check_outputs(&app);
            }
            ticks += n;
            continue;
        }
        feed(&mut app, b, &mut out, &mut due);
    }
    feed(&mut app, b'\n', &mut out, &mut due);
    // blank lines end the `wait`s still running (input ends a wait early)
    let mut guard = 0;
    while app.busy() {
        feed(&mut app, b' ', &mut out, &mut due);
        feed(&mut app, b'\n', &mut out, &mut due);
        guard += 1;
        assert!(guard < 10_000, "a wait never ends");
    }
    let finals = out.lines().filter(|l| is_final(l)).count();
    assert_eq!(finals, due, "replies at the end:\n{out}");
}
