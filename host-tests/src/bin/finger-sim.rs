//! finger-sim: the firmware's application (finger-fw's lib) on a simulated board.
//! Reads console lines from stdin, answers on stdout (the grammar of shared/CONSOLE.md),
//! exits at end of input. Time passes only through `wait <s>` (the control loop runs in
//! 1 ms steps), so runs are deterministic.
use std::io::{Read, Write};

use finger_fw::sim::SimBoard;
use finger_fw::App;

struct Out<W: Write>(W);

impl<W: Write> std::fmt::Write for Out<W> {
    fn write_str(&mut self, s: &str) -> std::fmt::Result {
        self.0.write_all(s.as_bytes()).map_err(|_| std::fmt::Error)
    }
}

fn main() {
    let mut app = App::new(SimBoard::default());
    let stdout = std::io::stdout();
    let mut out = Out(std::io::BufWriter::new(stdout.lock()));
    let mut stdin = std::io::stdin().lock();
    let mut buf = [0u8; 4096];
    loop {
        let n = match stdin.read(&mut buf) {
            Ok(0) => break,
            Ok(n) => n,
            Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
            Err(e) => {
                eprintln!("finger-sim: {e}");
                std::process::exit(1);
            }
        };
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
