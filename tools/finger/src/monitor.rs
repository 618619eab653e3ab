//! `finger monitor`: the board's `status` at a fixed rate, as a live terminal view (redrawn in
//! place on a terminal, one line per poll otherwise). On the simulated board, which nothing else
//! drives and whose time passes only through `wait`, a short demo ([`DEMO`]). Not here: the
//! console itself.
use std::io::Write;
use std::time::{Duration, Instant};

use crate::console::{CommandError, Console, Reply};

/// The view of one `status` reply: one `key  value` row per field.
pub fn render(r: &Reply, polls: u64, rate_hz: f64) -> String {
    let mut s = format!("finger monitor: status at {rate_hz} Hz, poll {polls} (Ctrl-C quits)\n\n");
    let width = r.fields().map(|(k, _)| k.len()).max().unwrap_or(0);
    for (k, v) in r.fields() {
        s.push_str(&format!("  {k:<width$}  {v}\n"));
    }
    s
}

/// What `finger --sim monitor` says on stderr before its demo.
pub const DEMO: &str = "finger monitor --sim: the simulated board is this client's own child and nothing else drives it, \
so this is a demo: armed, every channel at half its ceiling, the cable at 0.5 N; each poll runs the board's control \
loop for one period (`wait`), so the slew and the film's creep play out; Ctrl-C quits (the board stops with the client)";

/// The demo's setpoints on the simulated board: arm, every channel at half its ceiling
/// (`limits`' vmax), 0.5 N.
fn start_demo(con: &mut Console) -> Result<(), CommandError> {
    let vmax = con.command("limits")?.numbers("vmax").and_then(|v| v.first().copied()).unwrap_or(0.0);
    con.command("arm")?;
    con.command(&format!("volt all {}", (0.5 * vmax).floor()))?;
    con.command("force 0.5")?;
    Ok(())
}

/// Poll `status` every 1/rate_hz s, `count` times (forever when None), and draw each reply.
/// `demo` (the simulated board): set the demo's setpoints first and run the board's loop for a
/// period before each poll; `stop` after the last.
pub fn run(con: &mut Console, rate_hz: f64, count: Option<u64>, live: bool, demo: bool, out: &mut impl Write) -> Result<(), CommandError> {
    let period = Duration::from_secs_f64(1.0 / rate_hz);
    if demo {
        start_demo(con)?;
    }
    let mut next = Instant::now();
    let mut polls = 0;
    while count.is_none_or(|n| polls < n) {
        if demo {
            con.command(&format!("wait {}", period.as_secs_f64()))?;
        }
        let r = con.command("status")?;
        polls += 1;
        if live {
            // cursor home, clear screen, then the view
            let _ = write!(out, "\x1b[H\x1b[2J{}", render(&r, polls, rate_hz));
        } else {
            let _ = writeln!(out, "{}", r.line);
        }
        let _ = out.flush();
        next += period;
        let now = Instant::now();
        if next > now {
            std::thread::sleep(next - now);
        } else {
            next = now;
        }
    }
    if demo {
        con.command("stop")?;
    }
    Ok(())
}

#[cfg(test)]
mod tests {
    use super::*;

    #[test]
    fn the_view_has_a_row_per_field() {
        let r = Reply { before: vec![], line: "ok armed=0 force=0.000 volts=0.0,0.0,0.0".into() };
        let v = render(&r, 3, 5.0);
        assert!(v.contains("poll 3"));
        assert!(v.contains("  armed  0\n") && v.contains("  volts  0.0,0.0,0.0\n"), "{v}");
    }
}
