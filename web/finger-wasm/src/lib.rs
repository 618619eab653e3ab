//! The finger-fw application on a simulated board, compiled to WebAssembly for web/page.
//!
//! What it is: the glue finger-sim is (tools/finger-sim/src/main.rs), as `extern "C"`
//! exports: console bytes in through a buffer in linear memory, reply text out through
//! another, and time advanced by the page (`fw_tick`), in the control loop's 1 ms steps.
//! Input that arrives while a `wait` runs is held and fed when it ends, as the App asks.
//! Also the host's f64 model (`host_*`): the same finger-model in f64, for the page's
//! overlay; its replies use the console's key=value format (more digits).
//!
//! What it is not: a second application. Every board reply comes from `App`; only the
//! lines marked "glue" depend on the App's API.
//!
//! Protocol: write bytes at `io_buf()` (capacity `io_cap()`), call `fw_input(len)`; read
//! `out_len()` bytes at `out_ptr()`, then `out_clear()`. `host_*` write their reply there too.
//! `reply_parse(len)` reads a reply line written at `io_buf()` (the page parses every board's
//! replies here: the console protocol crate's parser).

use std::cell::RefCell;
use std::fmt::Write as _;

use finger_fw::app::{board_params, calibration_for};
use finger_fw::plant::Plant;
use finger_fw::sim::SimBoard;
use finger_fw::App;
use finger_model::inverse::stiffness_range;
use finger_model::{solve_pose, Finger, Method, Params, Pose, Solution};

const IO_CAP: usize = 4096;

struct State {
    app: App<SimBoard>,
    /// Bytes received while the App was busy (a `wait`).
    pending: Vec<u8>,
    out: String,
    /// A reply line's parts, as `reply_parse` read them.
    parsed: String,
    io: Vec<u8>,
    host: Params<f64>,
}

/// The simulated board with the HV plant behind its read-back, as finger-sim runs it (without
/// a plant, a board of the card that gives none).
fn plant_board() -> SimBoard {
    Plant::new(1).map_or_else(SimBoard::default, SimBoard::with_plant)
}

impl State {
    fn new() -> Self {
        State { app: App::new(plant_board()), pending: Vec::new(), out: String::new(), parsed: String::new(), io: vec![0; IO_CAP], host: board_params() }
    }

    /// Feed held bytes until the App is busy (glue: `busy`, `input_byte`).
    fn feed(&mut self) {
        let mut i = 0;
        while i < self.pending.len() && !self.app.busy() {
            self.app.input_byte(self.pending[i], &mut self.out);
            i += 1;
        }
        self.pending.drain(..i);
    }
}

thread_local! {
    static STATE: RefCell<State> = RefCell::new(State::new());
}

fn with<T>(f: impl FnOnce(&mut State) -> T) -> T {
    STATE.with(|s| f(&mut s.borrow_mut()))
}

/// The shared byte buffer for input (console bytes, parameter names).
#[no_mangle]
pub extern "C" fn io_buf() -> *mut u8 {
    with(|s| s.io.as_mut_ptr())
}

#[no_mangle]
pub extern "C" fn io_cap() -> u32 {
    IO_CAP as u32
}

#[no_mangle]
pub extern "C" fn out_ptr() -> *const u8 {
    with(|s| s.out.as_ptr())
}

#[no_mangle]
pub extern "C" fn out_len() -> u32 {
    with(|s| s.out.len() as u32)
}

#[no_mangle]
pub extern "C" fn out_clear() {
    with(|s| s.out.clear())
}

// ------------------------------------------------------------------ reply lines

/// The page's parser of reply lines (web/page/app.js, whichever board answers): the line at
/// `io_buf()[..len]` read by the console protocol crate. 0: not a final line; 1: `ok`, its
/// fields at `parsed_ptr()` (`parsed_len()` bytes), one `key=value` a line; 2: `err`, its code,
/// a newline, its message.
#[no_mangle]
pub extern "C" fn reply_parse(len: u32) -> u32 {
    use finger_protocol::reply::{Error, Reply};
    with(|s| {
        let n = (len as usize).min(IO_CAP);
        let line = String::from_utf8_lossy(&s.io[..n]).into_owned();
        s.parsed.clear();
        match Reply::parse(&line) {
            Ok(Reply::Ok(f)) => {
                for (k, v) in f.pairs() {
                    let _ = writeln!(s.parsed, "{k}={v}");
                }
                1
            }
            Ok(Reply::Err { code, message }) => {
                let _ = write!(s.parsed, "{code}\n{message}");
                2
            }
            Err(Error::NoCode) => {
                let _ = writeln!(s.parsed, "{}", line.trim().strip_prefix("err ").unwrap_or(&line).trim());
                2
            }
            Err(_) => 0,
        }
    })
}

#[no_mangle]
pub extern "C" fn parsed_ptr() -> *const u8 {
    with(|s| s.parsed.as_ptr())
}

#[no_mangle]
pub extern "C" fn parsed_len() -> u32 {
    with(|s| s.parsed.len() as u32)
}

/// A fresh board (power cycle): the App as `App::new` makes it.
#[no_mangle]
pub extern "C" fn fw_reset() {
    with(|s| {
        s.app = App::new(plant_board());
        s.pending.clear();
    })
}

/// Console bytes from `io_buf()[..len]`. Returns the bytes still held (a `wait` runs).
#[no_mangle]
pub extern "C" fn fw_input(len: u32) -> u32 {
    with(|s| {
        let n = (len as usize).min(IO_CAP);
        let bytes = s.io[..n].to_vec();
        s.pending.extend_from_slice(&bytes);
        s.feed();
        s.pending.len() as u32
    })
}

/// Advance the board's time by `ms` (the control loop in 1 ms steps; glue: `tick`).
#[no_mangle]
pub extern "C" fn fw_tick(ms: u32) {
    with(|s| {
        for _ in 0..ms.min(60_000) {
            s.app.tick(1, &mut s.out);
            if !s.pending.is_empty() && !s.app.busy() {
                s.feed();
            }
        }
    })
}

/// Board time, ms (glue: `now_ms`).
#[no_mangle]
pub extern "C" fn fw_now_ms() -> f64 {
    with(|s| s.app.now_ms() as f64)
}

// ------------------------------------------------------------------ host f64 model

/// The host's f64 finger at `p`, with the FE calibration the board gives those parameters
/// (`finger_fw::app::calibration_for`: the default finger is calibrated, docs/model.md "FE calibration").
fn host_finger(p: &Params<f64>) -> Result<Finger<f64>, finger_model::Error> {
    Finger::with_calibration(*p, calibration_for(p))
}

/// Host model parameters back to the board's defaults (the default finger on the board's film).
#[no_mangle]
pub extern "C" fn host_reset() {
    with(|s| s.host = board_params())
}

/// Set host parameter `io_buf()[..len]` (a name) to `value`; 0 if set, -1 if refused
/// (unknown name, out of range, read-only: the board's listing includes derived values).
#[no_mangle]
pub extern "C" fn host_param(len: u32, value: f64) -> i32 {
    with(|s| {
        let n = (len as usize).min(IO_CAP);
        let Ok(name) = std::str::from_utf8(&s.io[..n]) else { return -1 };
        let mut p = s.host;
        if p.set(name, value).is_err() || host_finger(&p).is_err() {
            return -1;
        }
        s.host = p;
        0
    })
}

fn write_pose(o: &mut String, p: &Pose<f64>) {
    let _ = write!(o, "{:.6},{:.6},{:.6}", p.x, p.y, p.theta.to_degrees());
}

/// Node and hinge-end poses of a solution, as `shape` reports them.
fn write_shape(o: &mut String, f: &Finger<f64>, sol: &Solution<f64>) {
    let n = sol.n;
    let p = f.params();
    let link_len = p.l - p.hinge_len();
    o.push_str(" nodes=");
    for k in 0..=n {
        if k > 0 {
            o.push(',');
        }
        write_pose(o, &sol.nodes[k]);
    }
    o.push_str(" hinges=");
    for k in 0..n {
        if k > 0 {
            o.push(',');
        }
        let (n1, q) = (sol.nodes[k + 1], sol.links[k]);
        let theta = n1.theta - q[2];
        let (s, c) = theta.sin_cos();
        let dx = link_len + q[0];
        write_pose(o, &Pose { x: n1.x - (c * dx - s * q[1]), y: n1.y - (s * dx + c * q[1]), theta });
    }
    let list = |o: &mut String, key: &str, v: &[f64]| {
        let _ = write!(o, " {key}=");
        for (i, x) in v.iter().enumerate() {
            let _ = write!(o, "{}{:.6}", if i > 0 { "," } else { "" }, x);
        }
    };
    list(o, "thick", &sol.thickness[..n]);
    let joints: Vec<f64> = sol.joint_angle[..n].iter().map(|a| a.to_degrees()).collect();
    list(o, "joints", &joints);
}

fn write_err(o: &mut String, e: &finger_model::Error) {
    let _ = finger_protocol::reply::emit_err_head(o, &e.code());
    let _ = write!(o, "{e}");
}

/// `solve` and `shape` in one, in f64: `ok nodes=.. hinges=.. thick=.. joints=.. stiffness=kxx,kyy,ktt`
/// or `err <code>: ..`.
#[no_mangle]
pub extern "C" fn host_shape(p: f64, v1: f64, v2: f64, v3: f64) {
    with(|s| {
        let mut o = String::from("ok");
        let r = host_finger(&s.host).and_then(|f| {
            let sol = f.solve(p, &[v1, v2, v3][..f.params().n.min(3)], Method::converged())?;
            let k = f.tip_stiffness(&sol)?;
            write_shape(&mut o, &f, &sol);
            let _ = write!(o, " stiffness={:.6e},{:.6e},{:.6e}", k[0][0], k[1][1], k[2][2]);
            Ok(())
        });
        match r {
            Ok(()) => s.out.push_str(&o),
            Err(e) => write_err(&mut s.out, &e),
        }
        s.out.push('\n');
    })
}

/// The inverse in f64 at tension `p` (NaN: the model's own choice): `ok force=.. volts=..
/// range=lo,hi stiffness=kxx,kyy,ktt ends=kyy_lo,kyy_hi` or `err <code>: ..`.
#[no_mangle]
pub extern "C" fn host_pose(d1: f64, d2: f64, d3: f64, p: f64) {
    with(|s| {
        let mut o = String::from("ok");
        let r = host_finger(&s.host).and_then(|f| {
            let angles = [d1.to_radians(), d2.to_radians(), d3.to_radians()];
            let sol = solve_pose(&f, &angles, if p.is_nan() { None } else { Some(p) })?;
            let k = f.tip_stiffness(&sol.to_solution(&f)?)?;
            let v = &sol.volts;
            let _ = write!(o, " force={:.6} volts={:.3},{:.3},{:.3} range={:.6},{:.6}", sol.tension, v[0], v[1], v[2], sol.interval[0], sol.interval[1]);
            let _ = write!(o, " stiffness={:.6e},{:.6e},{:.6e}", k[0][0], k[1][1], k[2][2]);
            if let Ok(sr) = stiffness_range(&f, &sol) {
                let _ = write!(o, " ends={:.6e},{:.6e}", sr.stiffness[0][1][1], sr.stiffness[1][1][1]);
            }
            Ok(())
        });
        match r {
            Ok(()) => s.out.push_str(&o),
            Err(e) => write_err(&mut s.out, &e),
        }
        s.out.push('\n');
    })
}
