//! The byte link to a board: a serial port, finger-sim's stdin/stdout, or QEMU's console socket.
//!
//! Every link is split into a writer and a reader; a thread turns the reader into lines on a
//! channel, so a read waits at most until its deadline, whatever the transport. Not here: the
//! console grammar (`console.rs`).
use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::mpsc::{self, Receiver, RecvTimeoutError};
use std::time::{Duration, Instant};

/// What went wrong on the link itself (not a board's `err` reply).
#[derive(Debug)]
pub enum LinkError {
    /// No line from the board within the time-out.
    Timeout(Duration),
    /// The board's side closed (process ended, port gone).
    Closed,
    /// Opening the link failed.
    Open(String),
    Io(std::io::Error),
}

impl std::fmt::Display for LinkError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            LinkError::Timeout(d) => write!(f, "the board did not answer within {:.1} s", d.as_secs_f64()),
            LinkError::Closed => write!(f, "the board's link closed"),
            LinkError::Open(s) => write!(f, "cannot open the link: {s}"),
            LinkError::Io(e) => write!(f, "link i/o: {e}"),
        }
    }
}

impl std::error::Error for LinkError {}

impl From<std::io::Error> for LinkError {
    fn from(e: std::io::Error) -> Self {
        LinkError::Io(e)
    }
}

/// A console link: lines out, lines in with a deadline.
pub struct Link {
    tx: Box<dyn Write + Send>,
    rx: Receiver<std::io::Result<String>>,
    /// What keeps the far side alive (finger-sim or QEMU), ended on drop.
    child: Option<Child>,
    /// QEMU's defmt log file and socket directory, removed on drop.
    scratch: Option<PathBuf>,
}

impl Link {
    fn new(tx: Box<dyn Write + Send>, rx: Box<dyn Read + Send>, child: Option<Child>, scratch: Option<PathBuf>) -> Link {
        let (send, recv) = mpsc::channel();
        std::thread::spawn(move || {
            let mut r = BufReader::new(rx);
            loop {
                let mut buf = Vec::new();
                match r.read_until(b'\n', &mut buf) {
                    Ok(0) => break,
                    Ok(_) => {
                        let s = String::from_utf8_lossy(&buf).trim_end_matches(['\r', '\n']).to_owned();
                        if send.send(Ok(s)).is_err() {
                            break;
                        }
                    }
                    Err(e) if e.kind() == std::io::ErrorKind::Interrupted => continue,
                    // serial ports time out their reads; that is not an end
                    Err(e) if e.kind() == std::io::ErrorKind::TimedOut => continue,
                    Err(e) => {
                        let _ = send.send(Err(e));
                        break;
                    }
                }
            }
        });
        Link { tx, rx: recv, child, scratch }
    }

    /// A serial port (the real board), 8N1.
    pub fn serial(path: &str, baud: u32) -> Result<Link, LinkError> {
        let port = serialport::new(path, baud).timeout(Duration::from_millis(100)).open().map_err(|e| LinkError::Open(format!("{path}: {e}")))?;
        let rx = port.try_clone().map_err(|e| LinkError::Open(format!("{path}: {e}")))?;
        Ok(Link::new(Box::new(port), Box::new(rx), None, None))
    }

    /// finger-sim as a child process, over its stdin and stdout.
    pub fn sim(program: &Path) -> Result<Link, LinkError> {
        let mut child = Command::new(program)
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .map_err(|e| LinkError::Open(format!("{}: {e}", program.display())))?;
        let tx = child.stdin.take().expect("piped stdin");
        let rx = child.stdout.take().expect("piped stdout");
        Ok(Link::new(Box::new(tx), Box::new(rx), Some(child), None))
    }

    /// A console on a Unix socket that something else serves (QEMU started by hand with
    /// `-chardev socket,id=con,path=SOCK,server=on -serial chardev:con`).
    pub fn socket(path: &Path) -> Result<Link, LinkError> {
        let s = UnixStream::connect(path).map_err(|e| LinkError::Open(format!("{}: {e}", path.display())))?;
        let rx = s.try_clone()?;
        Ok(Link::new(Box::new(s), Box::new(rx), None, None))
    }

    /// The firmware's emulator image booted in QEMU netduinoplus2 (deterministic `-icount`),
    /// its console on a private Unix socket, its defmt log (semihosting) in `defmt_log`.
    /// Waits for the boot banner.
    pub fn qemu(elf: &Path, defmt_log: &Path, timeout: Duration) -> Result<Link, LinkError> {
        if !elf.exists() {
            return Err(LinkError::Open(format!("{}: no firmware image (build it with `cargo build --release` at the top)", elf.display())));
        }
        let nanos = std::time::SystemTime::now().duration_since(std::time::UNIX_EPOCH).map_or(0, |d| d.subsec_nanos());
        let dir = std::env::temp_dir().join(format!("finger-client-{}-{nanos}", std::process::id()));
        std::fs::create_dir_all(&dir)?;
        let sock = dir.join("con.sock");
        let log = std::fs::File::create(defmt_log)?;
        let mut child = Command::new("qemu-system-arm")
            .args(["-machine", "netduinoplus2", "-cpu", "cortex-m4", "-display", "none", "-monitor", "none"])
            .arg("-chardev")
            .arg(format!("socket,id=con,path={},server=on,wait=on", sock.display()))
            .args(["-serial", "chardev:con", "-icount", "shift=0,sleep=off"])
            .args(["-semihosting-config", "enable=on,target=native", "-kernel"])
            .arg(elf)
            .stdin(Stdio::null())
            .stdout(log)
            .stderr(Stdio::piped())
            .spawn()
            .map_err(|e| LinkError::Open(format!("qemu-system-arm: {e} (scripts/setup installs it)")))?;
        // QEMU's own messages pass to stderr, but not its notice that the socket waits for us
        // (`qemu-system-arm: -chardev ...: info: QEMU waiting for connection on: ...`)
        if let Some(err) = child.stderr.take() {
            std::thread::spawn(move || {
                use std::io::BufRead;
                for l in std::io::BufReader::new(err).lines().map_while(Result::ok) {
                    if !l.contains("info: QEMU waiting for connection") {
                        eprintln!("{l}");
                    }
                }
            });
        }
        let t0 = Instant::now();
        let stream = loop {
            match UnixStream::connect(&sock) {
                Ok(s) => break s,
                Err(_) if matches!(child.try_wait(), Ok(Some(_))) => {
                    return Err(LinkError::Open("qemu-system-arm ended before its console opened".into()));
                }
                Err(_) if t0.elapsed() < timeout => std::thread::sleep(Duration::from_millis(20)),
                Err(e) => {
                    let _ = child.kill();
                    return Err(LinkError::Open(format!("QEMU's console socket: {e}")));
                }
            }
        };
        let rx = stream.try_clone()?;
        let mut link = Link::new(Box::new(stream), Box::new(rx), Some(child), Some(dir));
        let banner = link.line(timeout)?;
        if !banner.starts_with("# ") {
            return Err(LinkError::Open(format!("unexpected boot line from QEMU: {banner:?}")));
        }
        Ok(link)
    }

    /// Write bytes to the board.
    pub fn send(&mut self, bytes: &[u8]) -> Result<(), LinkError> {
        self.tx.write_all(bytes).map_err(|e| match e.kind() {
            std::io::ErrorKind::BrokenPipe => LinkError::Closed,
            _ => LinkError::Io(e),
        })?;
        self.tx.flush()?;
        Ok(())
    }

    /// The next line from the board, or `Timeout` when none comes within `timeout`.
    pub fn line(&mut self, timeout: Duration) -> Result<String, LinkError> {
        match self.rx.recv_timeout(timeout) {
            Ok(Ok(s)) => Ok(s),
            Ok(Err(e)) => Err(LinkError::Io(e)),
            Err(RecvTimeoutError::Timeout) => Err(LinkError::Timeout(timeout)),
            Err(RecvTimeoutError::Disconnected) => Err(LinkError::Closed),
        }
    }
}

impl Drop for Link {
    fn drop(&mut self) {
        if let Some(c) = self.child.as_mut() {
            let _ = c.kill();
            let _ = c.wait();
        }
        if let Some(d) = self.scratch.take() {
            let _ = std::fs::remove_dir_all(d);
        }
    }
}
