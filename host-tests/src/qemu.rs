//! The firmware's emulator images in QEMU with `-icount shift=0`: boot, talk to the console
//! over a Unix socket, read the defmt bytes (semihosting, QEMU's stdout) and, when a run asks
//! for it ([`Qemu::boot_traced`]), every register access in order (`-trace
//! memory_region_ops_write/read -D FILE`). Two images ([`Image`], built by [`crate::image`]):
//! the F405's (Cortex-M4F, netduinoplus2) and the Cortex-M3 image (netduino2).
//! [`qemu_command`] is the one QEMU command line every run starts from (these tests, the bench
//! runs of [`crate::perf`], the reports). Used by tests/qemu_*.rs and the `realtime_report`
//! and `fixed_report` examples.
//!
//! QEMU runs under a keeper ([`KEEPER`]): its log file is capped at [`LOG_CAP_BYTES`] (a run
//! that reaches it fails), and however the run ends (a finish, a failed assertion, the test process
//! killed) QEMU is stopped and the run's directory removed.
use crate::image::{image, Image};
use std::fs::File;
use std::io::{BufRead, BufReader, Read, Seek, Write};
use std::os::unix::net::UnixStream;
use std::path::{Path, PathBuf};
use std::process::{Child, Command, Stdio};
use std::time::{Duration, Instant};

/// TIM4 compare registers (HV channels 1..3) and the control tick's trace marker (CCR4).
pub const TIM4_CCR: [u64; 3] = [0x4000_0834, 0x4000_0838, 0x4000_083c];
pub const TIM4_ARR: u64 = 0x4000_082c;
pub const TICK_MARKER: u64 = 0x4000_0840;
pub const USART1_DR: u64 = 0x4001_1004;

/// `qemu-system-arm` on `machine` with `elf` loaded, semihosting on (its output on QEMU's
/// stdout) and `-icount <icount>` (deterministic instruction counts); ended after `timeout_s`
/// seconds (coreutils `timeout`) if given. The caller adds its display, console and log.
pub fn qemu_command(machine: &str, icount: &str, elf: &Path, timeout_s: Option<u32>) -> Command {
    let mut c = match timeout_s {
        Some(s) => {
            let mut c = Command::new("timeout");
            c.arg(s.to_string()).arg("qemu-system-arm");
            c
        }
        None => Command::new("qemu-system-arm"),
    };
    c.args(["-machine", machine, "-semihosting-config", "enable=on,target=native", "-icount", icount, "-kernel"]).arg(elf);
    c
}

/// One register access from the trace.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Access {
    pub write: bool,
    pub addr: u64,
    /// 0 when not `modelled`.
    pub value: u64,
    /// false: a register QEMU does not model on this machine (netduino2's RCC, GPIO): the
    /// access is in the log (`-d guest_errors`), in order, without its value.
    pub modelled: bool,
}

impl Access {
    /// A write of `value` to `addr` (any value where QEMU does not model the register).
    pub fn writes(&self, addr: u64, value: u64) -> bool {
        self.write && self.addr == addr && (!self.modelled || self.value == value)
    }
}

/// The most bytes QEMU's log file (the register trace and any `-d` output) may take
/// (`prlimit --fsize`: QEMU's writes past it fail; it blocks the SIGXFSZ that would end it);
/// a run whose log got there fails saying so. The traced tests write 0.03 to 12 MB each.
pub const LOG_CAP_BYTES: u64 = 256 << 20;

/// The keeper QEMU runs under (`sh -c KEEPER keeper DIR QEMU...`): QEMU with its stdin from
/// /dev/null; when the keeper's stdin closes (the harness ends the run, or its process is gone
/// however it ended) it stops QEMU (SIGTERM: the log is flushed), removes DIR and exits with
/// QEMU's status.
pub const KEEPER: &str = r#"dir=$1; shift; "$@" </dev/null & q=$!; cat >/dev/null; kill -TERM $q 2>/dev/null; wait $q; rc=$?; rm -rf "$dir"; exit $rc"#;

pub struct Qemu {
    /// The keeper (QEMU under it); its stdin, closed, ends the run.
    child: Child,
    con: BufReader<UnixStream>,
    tx: UnixStream,
    dir: PathBuf,
    /// QEMU's log file (`-D`), opened before QEMU started, so it is read at the end after the
    /// keeper removed the directory; `None`: no log asked for.
    log_file: Option<File>,
    /// The register trace is in the log.
    traced: bool,
    /// The log's cap, bytes.
    cap: u64,
    /// QEMU's stdout: the defmt bytes (semihosting).
    log: Option<std::thread::JoinHandle<Vec<u8>>>,
    /// The last boot banner (`# finger-fw <version> [config=..] ready`).
    pub banner: String,
}

impl Qemu {
    /// Boot the F405 image (no trace); returns after the banner.
    pub fn boot(tag: &str) -> Qemu {
        Self::boot_image(image(), tag)
    }

    /// Boot `img`'s release image (no trace).
    pub fn boot_on(img: Image, tag: &str) -> Qemu {
        Self::boot_image(img.elf(), tag)
    }

    /// Boot `img`'s release image with the register trace on ([`Qemu::finish`] reads it).
    pub fn boot_traced(img: Image, tag: &str) -> Qemu {
        Self::start(img.elf(), tag, &[], true, LOG_CAP_BYTES)
    }

    /// [`Qemu::boot_traced`] with its log capped at `cap_bytes` (the cap's own test).
    pub fn boot_traced_capped(img: Image, tag: &str, cap_bytes: u64) -> Qemu {
        Self::start(img.elf(), tag, &[], true, cap_bytes)
    }

    /// Boot `elf` (no trace).
    pub fn boot_image(elf: &Path, tag: &str) -> Qemu {
        Self::boot_with(elf, tag, &[])
    }

    /// Boot `elf` (its machine by its target) with `extra` QEMU arguments (no trace; a `-d`
    /// among them writes the log file, [`Qemu::finish_log`]).
    pub fn boot_with(elf: &Path, tag: &str, extra: &[&str]) -> Qemu {
        Self::start(elf, tag, extra, false, LOG_CAP_BYTES)
    }

    /// [`Qemu::boot_with`] with the register trace on.
    pub fn boot_traced_with(elf: &Path, tag: &str, extra: &[&str]) -> Qemu {
        Self::start(elf, tag, extra, true, LOG_CAP_BYTES)
    }

    /// The run's directory (sockets, log), removed when the run ends.
    pub fn dir(&self) -> &Path {
        &self.dir
    }

    fn start(elf: &Path, tag: &str, extra: &[&str], traced: bool, cap: u64) -> Qemu {
        let img = Image::of(elf);
        let dir = std::env::temp_dir().join(format!("finger-rt-{}-{img:?}-{tag}", std::process::id()));
        let _ = std::fs::remove_dir_all(&dir);
        std::fs::create_dir_all(&dir).unwrap();
        let sock = dir.join("con.sock");
        let [machine, cpu] = img.machine();
        let mut extra: Vec<String> = extra.iter().map(|a| a.to_string()).collect();
        // netduino2 leaves RCC and GPIO unmapped: its accesses there are guest errors, in the trace
        if traced && !img.models_gpio() {
            match extra.iter().position(|a| a == "-d") {
                Some(i) => extra[i + 1].push_str(",guest_errors"),
                None => extra.extend(["-d".into(), "guest_errors".into()]),
            }
        }
        let mut q = qemu_command(machine, "shift=0,sleep=off", elf, None);
        q.args(["-cpu", cpu, "-display", "none", "-monitor"])
            .arg(format!("unix:{},server=on,wait=off", dir.join("mon.sock").display()))
            .arg("-chardev")
            .arg(format!("socket,id=con,path={},server=on,wait=on", sock.display()))
            .args(["-serial", "chardev:con"]);
        if traced {
            q.args(["-trace", "memory_region_ops_write", "-trace", "memory_region_ops_read"]);
        }
        let log_file = (traced || extra.iter().any(|a| a == "-d")).then(|| {
            let path = dir.join("qemu.log");
            q.arg("-D").arg(&path);
            File::options().read(true).write(true).create(true).truncate(true).open(&path).unwrap()
        });
        q.args(&extra);
        let mut child = Command::new("sh")
            .args(["-c", KEEPER, "keeper"])
            .arg(&dir)
            .args(["prlimit", "--core=0", &format!("--fsize={cap}"), "--"])
            .arg(q.get_program())
            .args(q.get_args())
            .stdin(Stdio::piped())
            .stdout(Stdio::piped())
            .stderr(Stdio::null())
            .spawn()
            .expect("sh, prlimit, qemu-system-arm: run scripts/setup");
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
                    drop(child.stdin.take());
                    let _ = child.wait();
                    panic!("QEMU console socket: {e}");
                }
            }
        };
        stream.set_read_timeout(Some(Duration::from_secs(60))).unwrap();
        let tx = stream.try_clone().unwrap();
        let mut q = Qemu { child, con: BufReader::new(stream), tx, dir, log_file, traced, cap, log: Some(log), banner: String::new() };
        q.read_banner();
        q
    }

    /// The next console line is the boot banner ([`Qemu::banner`]): after a boot or a reset.
    pub fn read_banner(&mut self) {
        let banner = self.line();
        assert!(banner.starts_with("# finger-fw ") && banner.ends_with("ready"), "banner: {banner:?}");
        self.banner = banner;
    }

    /// One command to QEMU's monitor (HMP); what it answered within half a second.
    pub fn monitor(&mut self, command: &str) -> String {
        let mut mon = UnixStream::connect(self.dir.join("mon.sock")).expect("QEMU monitor socket");
        mon.set_read_timeout(Some(Duration::from_millis(500))).unwrap();
        mon.write_all(format!("{command}\n").as_bytes()).unwrap();
        let mut text = Vec::new();
        let mut buf = [0u8; 4096];
        while let Ok(k) = std::io::Read::read(&mut mon, &mut buf) {
            if k == 0 {
                break;
            }
            text.extend_from_slice(&buf[..k]);
        }
        String::from_utf8_lossy(&text).into_owned()
    }

    /// The monitor's `system_reset` (the CPU and devices reset, RAM as QEMU's reset leaves it:
    /// docs/firmware.md "Settings"); returns after the new boot banner ([`Qemu::banner`]).
    pub fn system_reset(&mut self) {
        self.monitor("system_reset");
        self.read_banner();
    }

    pub fn line(&mut self) -> String {
        let mut s = String::new();
        self.con.read_line(&mut s).expect("console read (timeout?)");
        assert!(!s.is_empty(), "console closed");
        s.trim_end_matches(['\r', '\n']).to_owned()
    }

    /// Send raw bytes.
    pub fn write(&mut self, bytes: &[u8]) {
        self.tx.write_all(bytes).unwrap();
    }

    /// Read lines until `n` final replies (ok/err); all lines read.
    pub fn finals(&mut self, n: usize) -> Vec<String> {
        let mut lines = Vec::new();
        let mut k = 0;
        while k < n {
            let l = self.line();
            if crate::reply::is_final(&l) {
                k += 1;
            }
            lines.push(l);
        }
        lines
    }

    /// One command, its final reply.
    pub fn cmd(&mut self, line: &str) -> String {
        self.write(format!("{line}\r\n").as_bytes());
        self.finals(1).pop().unwrap()
    }

    /// `n` words of guest memory from `addr` (QEMU's monitor, `xp`).
    pub fn read_words(&mut self, addr: u64, n: usize) -> Vec<u32> {
        let mut mon = UnixStream::connect(self.dir.join("mon.sock")).expect("QEMU monitor socket");
        mon.set_read_timeout(Some(Duration::from_millis(500))).unwrap();
        mon.write_all(format!("xp /{n}wx {addr:#x}\n").as_bytes()).unwrap();
        let mut text = String::new();
        let mut buf = [0u8; 65536];
        let t0 = Instant::now();
        // the reply ends when the last line (its address) has come, or on a quiet half second
        let last = format!("{:016x}:", addr + 4 * (n as u64 - (n as u64 - 1) % 4 - 1));
        while t0.elapsed() < Duration::from_secs(20) {
            match std::io::Read::read(&mut mon, &mut buf) {
                Ok(0) => break,
                Ok(k) => text.push_str(&String::from_utf8_lossy(&buf[..k])),
                Err(_) if text.contains(&last) => break,
                Err(_) => {}
            }
        }
        let mut words = Vec::new();
        for l in text.lines() {
            let Some((a, rest)) = l.split_once(':') else { continue };
            if u64::from_str_radix(a.trim(), 16).is_err() {
                continue;
            }
            words.extend(rest.split_whitespace().filter_map(|w| u32::from_str_radix(w.trim_start_matches("0x"), 16).ok()));
        }
        words.truncate(n);
        words
    }

    /// Bytes of the stack `[bottom, top)` written since reset, for a [`Image::paint_elf`]
    /// image: from `top` down to the lowest word that is no longer the paint (0xCCCCCCCC).
    pub fn stack_high_water(&mut self, bottom: u64, top: u64) -> u64 {
        let words = self.read_words(bottom, ((top - bottom) / 4) as usize);
        assert_eq!(words.len() as u64, (top - bottom) / 4, "monitor read");
        match words.iter().position(|&w| w != 0xCCCC_CCCC) {
            Some(i) => top - (bottom + 4 * i as u64),
            None => 0,
        }
    }

    /// Stop QEMU (SIGTERM: it flushes the trace); every register access, in order. Only for a
    /// run booted with the trace on.
    pub fn finish(self) -> Vec<Access> {
        assert!(self.traced, "no register trace: boot with Qemu::boot_traced");
        parse_trace(&self.finish_log())
    }

    /// Stop QEMU; the whole log file (trace and any `-d` output).
    pub fn finish_log(self) -> String {
        self.finish_all().0
    }

    /// Stop QEMU; the defmt bytes it wrote (semihosting, its stdout).
    pub fn finish_defmt(self) -> Vec<u8> {
        self.finish_all().1
    }

    /// Stop QEMU, reading nothing back.
    pub fn end(self) {}

    /// Close the keeper's stdin: QEMU stopped, the directory removed.
    fn stop(&mut self) {
        drop(self.child.stdin.take());
        let _ = self.child.wait();
        let _ = std::fs::remove_dir_all(&self.dir);
    }

    /// Bytes in QEMU's log file now (0 without one).
    pub fn log_size(&self) -> u64 {
        self.log_file.as_ref().and_then(|f| f.metadata().ok()).map_or(0, |m| m.len())
    }

    fn finish_all(mut self) -> (String, Vec<u8>) {
        self.stop();
        let size = self.log_size();
        assert!(size < self.cap, "QEMU's log reached the cap of {} bytes ({size}): the trace is cut (trace a shorter run)", self.cap);
        let mut text = String::new();
        if let Some(f) = self.log_file.as_mut() {
            let mut bytes = Vec::new();
            f.rewind().unwrap();
            f.read_to_end(&mut bytes).unwrap();
            text = String::from_utf8_lossy(&bytes).into_owned();
        }
        let defmt = self.log.take().map(|h| h.join().unwrap_or_default()).unwrap_or_default();
        (text, defmt)
    }
}

impl Drop for Qemu {
    fn drop(&mut self) {
        if self.child.stdin.is_some() {
            self.stop();
        }
    }
}

/// `memory_region_ops_{write,read} cpu 0 mr .. addr 0x.. value 0x.. size ..` lines, and
/// `Invalid {write,read} at addr 0x..,` (an unmodelled register, `-d guest_errors`).
pub fn parse_trace(text: &str) -> Vec<Access> {
    let mut v = Vec::new();
    for l in text.lines() {
        for (p, write) in [("Invalid write at addr 0x", true), ("Invalid read at addr 0x", false)] {
            if let Some(rest) = l.strip_prefix(p) {
                let hex = rest.split(',').next().unwrap_or("");
                if let Ok(addr) = u64::from_str_radix(hex.trim(), 16) {
                    v.push(Access { write, addr, value: 0, modelled: false });
                }
            }
        }
        let write = l.starts_with("memory_region_ops_write");
        if !write && !l.starts_with("memory_region_ops_read") {
            continue;
        }
        let field = |k: &str| -> Option<u64> {
            let mut it = l.split_whitespace();
            while let Some(w) = it.next() {
                if w == k {
                    return u64::from_str_radix(it.next()?.trim_start_matches("0x"), 16).ok();
                }
            }
            None
        };
        if let (Some(addr), Some(value)) = (field("addr"), field("value")) {
            v.push(Access { write, addr, value, modelled: true });
        }
    }
    v
}

/// The HV duties at every control tick: (tick number, duties before the tick's marker).
pub fn duties_per_tick(trace: &[Access]) -> Vec<[u64; 3]> {
    let mut d = [0u64; 3];
    let mut out = Vec::new();
    for a in trace.iter().filter(|a| a.write) {
        if let Some(ch) = TIM4_CCR.iter().position(|&r| r == a.addr) {
            d[ch] = a.value;
        } else if a.addr == TICK_MARKER {
            out.push(d);
        }
    }
    out
}

/// The largest duty step between consecutive ticks, any channel.
pub fn max_step(ticks: &[[u64; 3]]) -> u64 {
    ticks.windows(2).flat_map(|w| (0..3).map(move |c| w[0][c].abs_diff(w[1][c]))).max().unwrap_or(0)
}

/// TIM4's full-scale duty (ARR + 1), from the trace.
pub fn hv_full_scale(trace: &[Access]) -> u64 {
    trace.iter().rev().find(|a| a.write && a.addr == TIM4_ARR).map(|a| a.value + 1).expect("TIM4 ARR written")
}

/// Each `stop` line read from USART1 (its terminating CR/LF read): how many control ticks ran
/// from that read until all three duties were written 0 (0: within the same tick), and
/// whether any duty was written non-zero after it (before `until` accesses).
pub fn stop_latencies(trace: &[Access]) -> Vec<(usize, bool)> {
    let mut res = Vec::new();
    for (i, line) in lines_read(trace) {
        let word: String = line.trim().to_lowercase();
        if word.split_whitespace().next() == Some("stop") {
            let mut ticks = 0;
            let mut zero = [false; 3];
            let mut j = i + 1;
            while j < trace.len() && !zero.iter().all(|&z| z) {
                let w = trace[j];
                if w.write && w.addr == TICK_MARKER {
                    ticks += 1;
                }
                if let Some(ch) = TIM4_CCR.iter().position(|&r| r == w.addr && w.write) {
                    zero[ch] = w.value == 0;
                }
                j += 1;
            }
            // after the stop: any non-zero duty written in the next 50 ticks?
            let mut later_nonzero = false;
            let mut t = 0;
            for w in &trace[j..] {
                if w.write && w.addr == TICK_MARKER {
                    t += 1;
                    if t > 50 {
                        break;
                    }
                }
                if w.write && TIM4_CCR.contains(&w.addr) && w.value != 0 {
                    later_nonzero = true;
                }
            }
            res.push((ticks, later_nonzero));
        }
    }
    res
}

/// Bytes written to USART1 after the first `stop` line was read.
pub fn tx_bytes_after_stop(trace: &[Access]) -> usize {
    for (i, line) in lines_read(trace) {
        if line.trim().to_lowercase().starts_with("stop") {
            return trace[i..].iter().filter(|w| w.write && w.addr == USART1_DR).count();
        }
    }
    0
}

/// The lines read from USART1: (index in `trace` of the read of the line's CR or LF, the text
/// before it); an empty text between CR and LF.
fn lines_read(trace: &[Access]) -> Vec<(usize, String)> {
    let mut lines = Vec::new();
    let mut last: Vec<u8> = Vec::new();
    for (i, a) in trace.iter().enumerate() {
        if a.write || a.addr != USART1_DR {
            continue;
        }
        let b = a.value as u8;
        if b == b'\r' || b == b'\n' {
            lines.push((i, String::from_utf8_lossy(&last).into_owned()));
            last.clear();
        } else {
            last.push(b);
        }
    }
    lines
}
