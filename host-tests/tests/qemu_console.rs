//! The real firmware release image (feature `qemu`, the default) booted in QEMU netduinoplus2
//! (an STM32F405) with `-icount shift=0`: the console over a Unix socket (loopback only),
//! the bad inputs included, and the defmt log (semihosting, QEMU's stdout) decoded with
//! defmt-decoder. The test builds the image itself (`cargo build --release` at the workspace
//! root). A missing QEMU fails the test: run scripts/setup.
use std::io::{BufRead, BufReader, Read, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::sync::OnceLock;
use std::time::{Duration, Instant};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").canonicalize().unwrap()
}

fn target_dir() -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(d) if Path::new(&d).is_absolute() => PathBuf::from(d),
        Some(d) => std::env::current_dir().unwrap().join(d),
        None => root().join("target"),
    }
}

/// Build the emulator image once per test binary; its path.
fn image() -> &'static Path {
    static IMG: OnceLock<PathBuf> = OnceLock::new();
    IMG.get_or_init(|| {
        let tdir = target_dir();
        let out = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()))
            .current_dir(root())
            .env("CARGO_TARGET_DIR", &tdir)
            .args(["build", "--release", "--quiet", "--bin", "finger-fw"])
            .output()
            .expect("cargo");
        assert!(out.status.success(), "firmware build failed:\n{}", String::from_utf8_lossy(&out.stderr));
        tdir.join("thumbv7em-none-eabihf").join("release").join("finger-fw")
    })
}

struct Qemu {
    child: Child,
    con: BufReader<UnixStream>,
    tx: UnixStream,
    log: std::thread::JoinHandle<Vec<u8>>,
    _dir: PathBuf,
}

impl Qemu {
    fn boot() -> Qemu {
        let elf = image();
        if Command::new("qemu-system-arm").arg("--version").output().is_err() {
            panic!("qemu-system-arm not found: run scripts/setup (it installs QEMU from the distribution's packages)");
        }
        let dir = std::env::temp_dir().join(format!("finger-qemu-{}-{:?}", std::process::id(), std::thread::current().id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let sock = dir.join("con.sock");
        let mut child = Command::new("qemu-system-arm")
            .args(["-machine", "netduinoplus2", "-cpu", "cortex-m4", "-display", "none", "-monitor", "none"])
            .arg("-chardev")
            .arg(format!("socket,id=con,path={},server=on,wait=on", sock.display()))
            .args(["-serial", "chardev:con"])
            .args(["-icount", "shift=0,sleep=off"])
            .args(["-semihosting-config", "enable=on,target=native"])
            .arg("-kernel")
            .arg(elf)
            .stdin(Stdio::null())
            .stdout(Stdio::piped())
            .stderr(Stdio::inherit())
            .spawn()
            .expect("qemu-system-arm: run scripts/setup");
        let mut stdout = child.stdout.take().unwrap();
        let log = std::thread::spawn(move || {
            let mut v = Vec::new();
            let _ = stdout.read_to_end(&mut v);
            v
        });
        let t0 = Instant::now();
        let stream = loop {
            match UnixStream::connect(&sock) {
                Ok(s) => break s,
                Err(_) if t0.elapsed() < Duration::from_secs(20) => std::thread::sleep(Duration::from_millis(20)),
                Err(e) => {
                    let _ = child.kill();
                    panic!("QEMU console socket: {e}");
                }
            }
        };
        stream.set_read_timeout(Some(Duration::from_secs(30))).unwrap();
        let tx = stream.try_clone().unwrap();
        let mut q = Qemu { child, con: BufReader::new(stream), tx, log, _dir: dir };
        let banner = q.line();
        assert!(banner.starts_with("# finger-fw ") && banner.ends_with("ready"), "banner: {banner:?}");
        q
    }

    fn line(&mut self) -> String {
        let mut s = String::new();
        self.con.read_line(&mut s).expect("console read (timeout?)");
        assert!(!s.is_empty(), "console closed");
        s.trim_end_matches(['\r', '\n']).to_owned()
    }

    /// Send raw bytes (one or more lines); read `n` final replies, with any lines before them.
    fn send(&mut self, bytes: &[u8], n: usize) -> Vec<String> {
        self.tx.write_all(bytes).unwrap();
        let mut lines = Vec::new();
        let mut finals = 0;
        while finals < n {
            let l = self.line();
            if l.starts_with("ok") || l.starts_with("err ") {
                finals += 1;
            }
            lines.push(l);
        }
        lines
    }

    /// One command, its final reply.
    fn cmd(&mut self, line: &str) -> String {
        self.send(format!("{line}\r\n").as_bytes(), 1).pop().unwrap()
    }

    /// Stop QEMU; the defmt bytes it wrote.
    fn finish(mut self) -> Vec<u8> {
        let _ = self.child.kill();
        let _ = self.child.wait();
        self.log.join().unwrap()
    }
}

fn expect(q: &mut Qemu, line: &str, prefix: &str) -> String {
    let r = q.cmd(line);
    assert!(r.starts_with(prefix), "{line:?} -> {r:?}, wanted {prefix:?}");
    r
}

#[test]
fn qemu_console_commands_and_bad_inputs() {
    let mut q = Qemu::boot();
    let v = expect(&mut q, "version", "ok version=");
    assert!(v.contains("board=qemu-netduinoplus2"), "{v}");
    let help = q.send(b"help\n", 1);
    assert!(help.len() > 10 && help.last().unwrap() == "ok", "{help:?}");
    let s = expect(&mut q, "status", "ok armed=0 ");
    assert!(s.contains(" fault=none") && s.contains(" enable=0"), "{s}");
    expect(&mut q, "limits", "ok vmax=10000.0,10000.0,10000.0 vpullin=");
    expect(&mut q, "solve 0.5 0 1000 2000", "ok joints=");
    // bad inputs
    expect(&mut q, "frobnicate", "err unknown:");
    expect(&mut q, "solve nan 0 0 0", "err bad-number:");
    expect(&mut q, "solve inf 0 0 0", "err bad-number:");
    expect(&mut q, "solve 0x10 0 0 0", "err bad-number:");
    expect(&mut q, "solve 1.5abc 0 0 0", "err bad-number:");
    expect(&mut q, "solve 1e999 0 0 0", "err bad-number:");
    expect(&mut q, "solve -1 0 0 0", "err usage:");
    expect(&mut q, "solve 1e9 0 0 0", "err limit:");
    let r = q.send(b"\xff\xfe\x80garbage\r\n", 1);
    assert!(r[0].starts_with("err unknown:"), "{r:?}");
    let long = format!("{}\n", "x".repeat(400));
    let r = q.send(long.as_bytes(), 1);
    assert_eq!(r.len(), 1);
    assert!(r[0].starts_with("err too-long:"), "{r:?}");
    // CR, LF, CRLF: one reply each; blank lines none
    let r = q.send(b"version\rversion\nversion\r\n\r\n\n", 3);
    assert_eq!(r.len(), 3, "{r:?}");
    expect(&mut q, "volt 1 100", "err not-armed:");
    expect(&mut q, "force 0.5", "err not-armed:");
    expect(&mut q, "param l", "ok l=27");
    expect(&mut q, "param margin 1", "err usage:");
    expect(&mut q, "arm", "ok armed=1");
    expect(&mut q, "param l 30", "err armed:");
    expect(&mut q, "volt 1 10000", "err limit:");
    expect(&mut q, "volt 1 -1", "err usage:");
    expect(&mut q, "param slew 100000", "err armed:");
    expect(&mut q, "volt all 1000", "ok volts=1000.0,1000.0,1000.0");
    expect(&mut q, "wait 0.6", "ok waited=0.6");
    let s = expect(&mut q, "status", "ok armed=1 ");
    assert!(s.contains(" volts=1000.0,1000.0,1000.0 ") && s.contains(" enable=1"), "{s}");
    expect(&mut q, "force 0.5", "ok force=0.500 cable=");
    // pose (the inverse model on the target, armed: it sets the tension and the voltages) at a
    // posture of the host's model; the answer agrees with the host's inverse
    // the board's default finger: MODEL.md's, with its FE calibration
    let f = finger_model::Finger::with_calibration(finger_model::Params::<f32>::default(), finger_model::Calibration::model_md()).unwrap();
    let s = f.solve(0.8, &[1000.0, 3000.0, 5000.0], finger_model::Method::converged()).unwrap();
    let deg = [0, 1, 2].map(|k| format!("{:.6}", (s.joint_angle[k] as f64).to_degrees()).parse::<f64>().unwrap());
    // the firmware solves with the finger's branch table
    let opts = finger_model::inverse::Options::default();
    let table = finger_model::inverse::BranchTable::new(&f, &opts).unwrap();
    let rad = deg.map(|d| (d * std::f64::consts::PI / 180.0) as f32);
    let want = finger_model::inverse::solve_pose_tabled(&table, &rad, None).unwrap();
    let r = expect(&mut q, &format!("pose {} {} {}", deg[0], deg[1], deg[2]), "ok force=");
    let force: f64 = r.split_whitespace().find_map(|w| w.strip_prefix("force=")).unwrap().parse().unwrap();
    assert!((force - want.tension as f64).abs() < 2e-3, "{r} vs {want:?}");
    let s = expect(&mut q, "status", "ok armed=1 ");
    assert!(s.contains(&format!(" force={:.3} ", want.tension)), "{s}");
    expect(&mut q, "pose 20 5 5", "err unreachable:");
    expect(&mut q, "contact 1 1.5", "ok fx=");
    expect(&mut q, "stop", "ok stopped");
    let s = expect(&mut q, "status", "ok armed=0 force=0.000 volts=0.0,0.0,0.0 ");
    assert!(s.contains(" servo=0.00 ") && s.contains(" enable=0"), "{s}");
    expect(&mut q, "cal 1.540745 6.245597 1.066900 1.154625 0.718260 0.054631 5.254023 -1.756332", "ok cal=1.540745,6.245597,1.066900,1.154625,0.718260,0.054631,5.254023,-1.756332");
    expect(&mut q, "preset paper", "ok preset=paper");
    q.finish();
}

#[test]
fn qemu_defmt_log_decodes() {
    let mut q = Qemu::boot();
    expect(&mut q, "version", "ok version=");
    let bytes = q.finish();
    assert!(!bytes.is_empty(), "no defmt bytes on QEMU's stdout (semihosting)");
    let elf = std::fs::read(image()).unwrap();
    let table = defmt_decoder::Table::parse(&elf).unwrap().expect("the image has a .defmt table");
    let mut dec = table.new_stream_decoder();
    dec.received(&bytes);
    let mut messages = Vec::new();
    while let Ok(frame) = dec.decode() {
        messages.push(frame.display_message().to_string());
    }
    assert!(
        messages.iter().any(|m| m.contains("finger-fw") && m.contains("up") && m.contains("qemu-netduinoplus2")),
        "decoded: {messages:?}"
    );
}
