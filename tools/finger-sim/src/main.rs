//! finger-sim: the firmware's application (finger-fw's lib) on a simulated board.
//! Reads console lines from stdin, answers on stdout (the grammar of docs/console.md),
//! exits at end of input.
//!
//! - default: the board's time is the wall clock's while finger-sim waits for input: the
//!   board lives on between lines as a real one does (after `stop` its stacks discharge, the
//!   film creeps), the milliseconds it waited ticked when the next bytes arrive (at most
//!   [`IDLE_MAX_MS`] at a time); a line itself takes no time, and `wait <s>` runs s seconds of
//!   1 ms control ticks at once. Input that arrives in one piece (a script piped in) has no
//!   waits between its lines, so its replies are the same on any machine.
//! - `--virtual`: the real-time core in virtual time (`finger_fw::sim::VirtualSim`): all of
//!   stdin goes onto the wire at once and arrives at 115200 baud, the control core ticks every
//!   1 ms while commands run, each command takes its modelled time (`sim::default_cost`), a
//!   `stop` acts the moment its line ends. At the end it prints `# t=<ms> ticks=<n>` on stderr.
//!
//! `--help` prints the usage; any other argument is refused (exit status 2). Typed at a
//! terminal, it greets on stderr (what it is, `help`, how to quit); piped, it prints nothing
//! but the board's replies.
use std::io::{IsTerminal, Read, Write};
use std::time::Instant;

use finger_fw::plant::Plant;
use finger_fw::sim::{default_cost, SimBoard, VirtualSim};
use finger_fw::App;

/// The longest wait for input ticked on the board at once, ms (10 min: the stacks have
/// discharged and the film has relaxed long before).
const IDLE_MAX_MS: u128 = 600_000;

struct Out<W: Write>(W);

impl<W: Write> std::fmt::Write for Out<W> {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.0.write_all(s.as_bytes()).map_err(|_| std::fmt::Error)
    }
}

const USAGE: &str = "\
usage: finger-sim [--virtual]
  The driver board's application on a simulated board: console lines on stdin, replies on
  stdout (docs/console.md). Exits at the end of input (Ctrl-D at a terminal). The board's time
  runs with the wall clock while it waits for input (a line takes none; `wait <s>` runs s
  seconds at once), so a script piped in whole answers the same on any machine.
  --virtual   the real-time core in virtual time: input at 115200 baud, 1 ms control ticks,
              each command taking its modelled time; `# t=<ms> ticks=<n>` on stderr at the end
  --help      this text";

/// `Ok(virtual_time)`, or the exit status after printing usage.
fn parse_args(args: impl Iterator<Item = String>) -> Result<bool, u8> {
    let mut virtual_time = false;
    for a in args {
        match a.as_str() {
            "--virtual" => virtual_time = true,
            "-h" | "--help" => {
                println!("{USAGE}");
                return Err(0);
            }
            other => {
                eprintln!("finger-sim: unknown argument `{other}`\n{USAGE}");
                return Err(2);
            }
        }
    }
    Ok(virtual_time)
}

fn main() {
    let virtual_time = match parse_args(std::env::args().skip(1)) {
        Ok(v) => v,
        Err(code) => std::process::exit(code.into()),
    };
    if std::io::stdin().is_terminal() {
        eprintln!(
            "finger-sim {}: the finger board's console on a simulated board (no hardware). Type `help` for the commands; Ctrl-D quits.",
            finger_fw::VERSION
        );
    }
    let stdout = std::io::stdout();
    let mut out = Out(std::io::BufWriter::new(stdout.lock()));
    let mut stdin = std::io::stdin().lock();
    if virtual_time {
        let mut input = Vec::new();
        if let Err(e) = stdin.read_to_end(&mut input) {
            eprintln!("finger-sim: {e}");
            std::process::exit(1);
        }
        let mut sim = VirtualSim::new(default_cost);
        let mut ticks = 0u64;
        for chunk in input.chunks(8192) {
            while !sim.send(chunk) {
                let t = sim.t_us + 1000;
                sim.run_until(t, &mut out, &mut |_, _| ticks += 1);
            }
        }
        sim.run_idle(3_600_000_000, &mut out, &mut |_, _| ticks += 1);
        let _ = out.0.flush();
        eprintln!("# t={} ticks={ticks}", sim.t_us / 1000);
        return;
    }
    // the HV plant behind the board's read-back (docs/firmware.md "The plant": `plant ...`)
    let Some(plant) = Plant::new(1) else {
        eprintln!("finger-sim: the board's film card gives no plant");
        std::process::exit(1);
    };
    let mut app = App::new(SimBoard::with_plant(plant));
    let mut buf = [0u8; 4096];
    loop {
        let idle = Instant::now();
        let n = match stdin.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => {
                eprintln!("finger-sim: {e}");
                std::process::exit(1);
            }
        };
        // the board lived on while nothing arrived
        let idle_ms = idle.elapsed().as_millis().min(IDLE_MAX_MS) as u32;
        if idle_ms > 0 {
            app.tick(idle_ms, &mut out);
        }
        for &b in &buf[..n] {
            app.input_byte(b, &mut out);
            while app.busy() {
                app.tick(1, &mut out);
            }
        }
        let _ = out.0.flush();
    }
    let _ = out.0.flush();
}
