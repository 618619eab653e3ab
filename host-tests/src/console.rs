//! One console as the tests drive it, whichever board answers: the application on the
//! simulated board (`App<SimBoard>`, [`crate::sim_console`]) or a firmware image in QEMU
//! ([`crate::qemu::Qemu`]). A check written once against [`Console`] runs on both; the
//! replies are read with [`crate::reply`]. Not a client: tools/finger is what a user runs.
use crate::reply::field;
use finger_fw::sim::SimBoard;
use finger_fw::App;

/// A console: one command line in, its final reply line (`ok ...` or `err <code>: ...`) out.
pub trait Console {
    fn cmd(&mut self, line: &str) -> String;
}

impl Console for App<SimBoard> {
    fn cmd(&mut self, line: &str) -> String {
        crate::sim_console::cmd(self, line)
    }
}

impl Console for crate::qemu::Qemu {
    fn cmd(&mut self, line: &str) -> String {
        crate::qemu::Qemu::cmd(self, line)
    }
}

/// `line`'s reply, asserting it starts with `prefix`.
pub fn expect<C: Console + ?Sized>(c: &mut C, line: &str, prefix: &str) -> String {
    let r = c.cmd(line);
    assert!(r.starts_with(prefix), "{line:?} -> {r:?}, wanted {prefix:?}");
    r
}

/// `line`'s reply, asserting it is `ok` or `ok ...`.
pub fn ok<C: Console + ?Sized>(c: &mut C, line: &str) -> String {
    let r = c.cmd(line);
    assert!(r == "ok" || r.starts_with("ok "), "{line:?} -> {r}");
    r
}

/// `line`'s reply, asserting it is `err <code>: ...`.
pub fn err<C: Console + ?Sized>(c: &mut C, line: &str, code: &str) -> String {
    let r = c.cmd(line);
    assert!(r.starts_with(&format!("err {code}: ")), "{line:?} -> {r} (wanted {code})");
    r
}

/// Each `(line, code)`: `line`'s reply is `err <code>: ...`.
pub fn check_refusals<C: Console + ?Sized>(c: &mut C, refusals: &[(&str, &str)]) {
    for (line, code) in refusals {
        err(c, line, code);
    }
}

/// Refusals every console gives at its defaults, disarmed, and that change nothing.
pub const REFUSED_DISARMED: [(&str, &str); 11] = [
    ("frobnicate", "unknown"),
    ("solve nan 0 0 0", "bad-number"),
    ("solve inf 0 0 0", "bad-number"),
    ("solve 0x10 0 0 0", "bad-number"),
    ("solve 1.5abc 0 0 0", "bad-number"),
    ("solve 1e999 0 0 0", "bad-number"),
    ("solve -1 0 0 0", "usage"),
    ("solve 1e9 0 0 0", "limit"),
    ("volt 1 100", "not-armed"),
    ("force 0.5", "not-armed"),
    ("param margin 1", "usage"),
];

/// The ceiling in force on channel 1, V, as `limits` reports it (`vmax=`).
pub fn ceiling<C: Console + ?Sized>(c: &mut C) -> f64 {
    field(&expect(c, "limits", "ok vmax="), "vmax")[0]
}

/// Commands that would raise the model's own ceiling, or reset it: none may raise the one in force.
pub const CEILING_RAISERS: [&str; 9] = [
    "param g 1000", // a stiffer film: the model's ceiling rises a hundredfold
    "param z0 50",  // thicker layers
    "param eps_r 1",
    "param margin 0.999",
    "param v_supply 100000",
    "preset paper",
    "param g 1000",
    "cal none",
    "preset default",
];

/// The ceiling in force only ever lowers: as it is, then after each of [`CEILING_RAISERS`] and
/// `extra` (commands that touch the model: `param`, `preset`, `cal`), the ceiling is at most
/// `v0` (the ceiling at boot) and the card's hold ceiling `vhold`, `vhold_now` still reads
/// `vhold`, and, armed, each command of `refused(v0, vhold)` answers `err limit:`.
pub fn check_ceiling_only_lowers<C: Console + ?Sized>(
    c: &mut C,
    v0: f64,
    vhold: f64,
    extra: &[&str],
    vhold_now: impl Fn(&mut C) -> f64,
    refused: impl Fn(f64, f64) -> Vec<String>,
) {
    for line in [""].iter().chain(&CEILING_RAISERS).chain(extra) {
        if !line.is_empty() {
            expect(c, line, "ok ");
        }
        let v = ceiling(c);
        assert!(v <= v0 && v <= vhold, "after {line:?}: ceiling {v} past the board's {v0} or the card's hold ceiling {vhold}");
        assert_eq!(vhold_now(c), vhold, "{line}");
        expect(c, "arm", "ok armed=1");
        for r in refused(v0, vhold) {
            err(c, &r, "limit");
        }
        expect(c, "stop", "ok stopped");
    }
}
