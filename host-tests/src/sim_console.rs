//! The console of the application on a simulated board, as the host tests drive it: bytes in,
//! the control loop run through any `wait`, the reply lines out. Not a transport: finger-sim
//! and tools/finger are what a user runs. The checks shared with QEMU are in [`crate::console`].
use finger_fw::sim::SimBoard;
use finger_fw::App;

use crate::reply::is_final;

/// A reply sink for `App::input` and `App::tick`.
pub struct Out(pub String);

impl std::fmt::Write for Out {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.0.push_str(s);
        Ok(())
    }
}

/// Feed raw bytes, run the control loop through any `wait` after each; everything written.
pub fn feed_text(a: &mut App<SimBoard>, bytes: &[u8]) -> String {
    let mut out = Out(String::new());
    for &b in bytes {
        a.input_byte(b, &mut out);
        while a.busy() {
            a.tick(1, &mut out);
        }
    }
    out.0
}

/// As [`feed_text`], split into lines.
pub fn feed(a: &mut App<SimBoard>, bytes: &[u8]) -> Vec<String> {
    feed_text(a, bytes).lines().map(str::to_owned).collect()
}

/// One command line: its final reply line (asserting there is exactly one ok/err line, last).
pub fn cmd(a: &mut App<SimBoard>, line: &str) -> String {
    let lines = feed(a, format!("{line}\n").as_bytes());
    let finals: Vec<_> = lines.iter().filter(|l| is_final(l)).collect();
    assert_eq!(finals.len(), 1, "{line:?} -> {lines:?}");
    let last = lines.last().unwrap();
    assert!(is_final(last), "{line:?} -> {lines:?}");
    last.clone()
}

/// `frac` of the ceiling `vmax`, V, rounded down to a whole volt: a voltage as a test types it,
/// derived from the ceiling in force so that a test keeps its property whatever the board's card.
pub fn frac_of(vmax: f64, frac: f64) -> f32 {
    (vmax * frac).floor() as f32
}

/// A console line with its voltages given as fractions of the ceiling `vmax`: each word `@f`
/// becomes [`frac_of`]`(vmax, f)` (`"solve 1 @0.5 0 @0.9"`). Other words stay as they are.
pub fn at_ceiling(line: &str, vmax: f64) -> String {
    let word = |w: &str| match w.strip_prefix('@') {
        Some(f) => format!("{}", frac_of(vmax, f.parse().unwrap())),
        None => w.to_owned(),
    };
    line.split('\n').map(|l| l.split(' ').map(word).collect::<Vec<_>>().join(" ")).collect::<Vec<_>>().join("\n")
}
