//! `finger monitor`: the board's `status` at a fixed rate, as a live terminal view (redrawn in
//! place on a terminal, one line per poll otherwise). Not here: the console itself.
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

/// Poll `status` every 1/rate_hz s, `count` times (forever when None), and draw each reply.
pub fn run(con: &mut Console, rate_hz: f64, count: Option<u64>, live: bool, out: &mut impl Write) -> Result<(), CommandError> {
    let period = Duration::from_secs_f64(1.0 / rate_hz);
    let mut next = Instant::now();
    let mut polls = 0;
    while count.is_none_or(|n| polls < n) {
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
