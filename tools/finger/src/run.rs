//! `finger run scene.toml`: a scene's tensions and voltages on a board, next to the host's f64
//! model. Each posture goes through `solve` (model only, nothing moves) and, where the board has
//! it, `shape` (node poses for the plot); with `--drive` the board is also armed, driven with
//! `volt` and `force` to each posture, read back with `status`, and stopped at the end.
//!
//! The board first gets the scene's finger: `disarm`, `preset`, then `param` for each value
//! that differs. Not here: the scene format and the host model run (tools/finger-scene), the
//! console grammar (`console.rs`).
use std::sync::atomic::{AtomicBool, Ordering};
use std::time::{Duration, Instant};

use finger_model::params::PARAMS;
use finger_model::{Params, Pose};
use finger_scene::{Kind, RefPosture, Scene, SceneError, SceneResult};

use crate::console::{CommandError, Console, ErrorCode, Reply};

/// Why a run stopped.
#[derive(Debug)]
pub enum RunError {
    /// The scene file or the host model refused.
    Scene(SceneError),
    /// A command failed: the board refused it, or the link did.
    Command { line: String, error: CommandError },
    /// The board answered something this client cannot read, or cannot run this scene.
    Board(String),
    /// [`interrupt`] was called (Ctrl-C): the run stopped between two commands.
    Interrupted,
}

static INTERRUPTED: AtomicBool = AtomicBool::new(false);

/// Ask a run to stop at its next command (a Ctrl-C handler calls this); a driven run still
/// ends with `stop`. True if it had been asked already.
pub fn interrupt() -> bool {
    INTERRUPTED.swap(true, Ordering::SeqCst)
}

fn check_interrupt() -> Result<(), RunError> {
    if INTERRUPTED.load(Ordering::SeqCst) {
        Err(RunError::Interrupted)
    } else {
        Ok(())
    }
}

impl std::fmt::Display for RunError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            RunError::Scene(e) => write!(f, "{e}"),
            RunError::Command { line, error } => write!(f, "{line}: {error}"),
            RunError::Board(s) => write!(f, "{s}"),
            RunError::Interrupted => write!(f, "interrupted"),
        }
    }
}

impl std::error::Error for RunError {}

/// What the board answered for one posture.
#[derive(Clone, Debug, PartialEq)]
pub struct BoardPosture {
    pub tension: f64,
    pub volts: Vec<f64>,
    /// `solve`: joint angles, deg.
    pub joints_deg: Vec<f64>,
    /// `solve`: tip x, y mm, angle deg.
    pub tip: [f64; 3],
    pub cable_mm: f64,
    pub thick_mm: Vec<f64>,
    /// `solve`: k_xx, k_yy N/mm, k_θθ N·mm/rad.
    pub stiffness: Vec<f64>,
    pub iters: f64,
    /// `shape`: the centreline (node 0, hinge 1's end, node 1, ..., the tip), mm; None when
    /// the board has no `shape`.
    pub points: Option<Vec<[f64; 2]>>,
    /// With `--drive`: `status` once the board reached the posture.
    pub driven: Option<Driven>,
}

/// The board's `status` while driven to a posture.
#[derive(Clone, Debug, PartialEq)]
pub struct Driven {
    pub force: f64,
    pub volts: Vec<f64>,
    pub joints_deg: Vec<f64>,
    pub tip: [f64; 3],
    pub cable_mm: f64,
    /// The HV read-back, on a board with one (`status`' `vmeas=`, `imeas=`, `thick_meas=`):
    /// each channel's measured voltage (V), return current (µA) and sensed thickness (mm; NaN
    /// until measured).
    pub readback: Option<Readback>,
}

/// The HV read-back of one `status`.
#[derive(Clone, Debug, PartialEq)]
pub struct Readback {
    pub vmeas_v: Vec<f64>,
    pub imeas_ua: Vec<f64>,
    pub thick_meas_mm: Vec<f64>,
}

impl Readback {
    /// From a `status` reply: None without `vmeas=` (a board without a read-back).
    pub fn of(r: &Reply) -> Option<Readback> {
        // `-`: not measured yet (NaN)
        Some(Readback { vmeas_v: r.measured("vmeas")?, imeas_ua: r.measured("imeas")?, thick_meas_mm: r.measured("thick_meas")? })
    }
}

/// A scene run on a board, with the host model's run of the same scene.
#[derive(Clone, Debug)]
pub struct BoardRun {
    pub host: SceneResult,
    pub board: Vec<BoardPosture>,
    pub drove: bool,
}

fn numbers(r: &Reply, key: &str, line: &str) -> Result<Vec<f64>, RunError> {
    r.numbers(key).ok_or_else(|| RunError::Board(format!("{line}: no numbers `{key}=` in `{}`", r.line)))
}

fn three(v: Vec<f64>, key: &str) -> Result<[f64; 3], RunError> {
    v.try_into().map_err(|_| RunError::Board(format!("`{key}=` is not x,y,deg")))
}

fn cmd(con: &mut Console, line: &str) -> Result<Reply, RunError> {
    check_interrupt()?;
    con.command(line).map_err(|error| RunError::Command { line: line.to_string(), error })
}

/// A number as the console reads it: integers plainly, others in shortest round-trip form.
fn num(x: f64) -> String {
    if x.fract() == 0.0 && x.abs() < 1e15 {
        format!("{}", x as i64)
    } else {
        format!("{x:?}")
    }
}

/// The board's parameter values (`param` lists `name=value (range)` lines).
fn board_params(con: &mut Console) -> Result<Vec<(String, f64)>, RunError> {
    let r = cmd(con, "param")?;
    Ok(r.before
        .iter()
        .filter_map(|l| {
            let (name, rest) = l.split_once('=')?;
            Some((name.trim().to_string(), rest.split_whitespace().next()?.parse().ok()?))
        })
        .collect())
}

/// Give the board the scene's finger: `disarm`, the preset whose DE rule it uses, then each
/// parameter that differs (retried while some succeed: the board checks the whole set after
/// each change, as the scene reader does), then `cal none`.
pub fn load_finger(con: &mut Console, p: &Params<f64>) -> Result<(), RunError> {
    cmd(con, "disarm")?;
    let paper = p.de_rule == Params::<f64>::paper().de_rule;
    cmd(con, if paper { "preset paper" } else { "preset default" })?;
    let on_board = board_params(con)?;
    let mut pending: Vec<(&str, f64)> = PARAMS
        .iter()
        .filter(|i| !i.read_only)
        .filter_map(|i| {
            let v = p.get(i.name)?;
            let b = on_board.iter().find(|(n, _)| n == i.name).map(|x| x.1);
            let same = b.is_some_and(|b| (b - v).abs() <= 1e-6 * v.abs().max(1.0));
            (!same).then_some((i.name, v))
        })
        .collect();
    while !pending.is_empty() {
        let before = pending.len();
        let mut failed = Vec::new();
        let mut first = None;
        for (name, v) in pending {
            let line = format!("param {name} {}", num(v));
            match con.command(&line) {
                Ok(_) => {}
                Err(error @ CommandError::Board { .. }) => {
                    first.get_or_insert(RunError::Command { line, error });
                    failed.push((name, v));
                }
                Err(error) => return Err(RunError::Command { line, error }),
            }
        }
        if failed.len() == before {
            return Err(first.expect("a failure was recorded"));
        }
        pending = failed;
    }
    // a scene's finger is the model as docs/model.md states it (the host's `Finger::new`, which the
    // continuum reference cross-checks): without the board's FE calibration (`cal`)
    cmd(con, "cal none")?;
    Ok(())
}

fn solve_line(verb: &str, tension: f64, volts: &[f64]) -> String {
    let v: Vec<String> = volts.iter().map(|&x| num(x)).collect();
    format!("{verb} {} {}", num(tension), v.join(" "))
}

/// `solve` (and `shape`, when the board has it) for one posture.
fn ask(con: &mut Console, tension: f64, volts: &[f64], has_shape: &mut bool) -> Result<BoardPosture, RunError> {
    let line = solve_line("solve", tension, volts);
    let r = cmd(con, &line)?;
    let mut b = BoardPosture {
        tension,
        volts: volts.to_vec(),
        joints_deg: numbers(&r, "joints", &line)?,
        tip: three(numbers(&r, "tip", &line)?, "tip")?,
        cable_mm: numbers(&r, "cable", &line)?.first().copied().unwrap_or(f64::NAN),
        thick_mm: numbers(&r, "thick", &line)?,
        stiffness: r.numbers("stiffness").unwrap_or_default(),
        iters: r.numbers("iters").and_then(|v| v.first().copied()).unwrap_or(f64::NAN),
        points: None,
        driven: None,
    };
    if *has_shape {
        let line = solve_line("shape", tension, volts);
        match con.command(&line) {
            Ok(r) => {
                let nodes = numbers(&r, "nodes", &line)?;
                let hinges = numbers(&r, "hinges", &line)?;
                let mut pts = Vec::new();
                for (k, node) in nodes.chunks(3).enumerate() {
                    pts.push([node[0], node[1]]);
                    if let Some(h) = hinges.chunks(3).nth(k) {
                        pts.push([h[0], h[1]]);
                    }
                }
                b.points = Some(pts);
            }
            Err(CommandError::Board { code: ErrorCode::Unknown, .. }) => *has_shape = false,
            Err(error) => return Err(RunError::Command { line, error }),
        }
    }
    Ok(b)
}

/// Drive the board to a posture (`volt`, `force`), wait until the channels have slewed there,
/// and read `status`.
fn drive_to(con: &mut Console, tension: f64, volts: &[f64], slew: f64) -> Result<Driven, RunError> {
    let r = cmd(con, "status")?;
    let now = numbers(&r, "volts", "status")?;
    let step = volts.iter().zip(&now).map(|(a, b)| (a - b).abs()).fold(0.0, f64::max);
    for (k, v) in volts.iter().enumerate() {
        cmd(con, &format!("volt {} {}", k + 1, num(*v)))?;
    }
    cmd(con, &format!("force {}", num(tension)))?;
    // the channels move at `slew` V/s; wait for them, with room for a slow host
    let deadline = Instant::now() + Duration::from_secs_f64(2.0 * step / slew) + con.timeout;
    loop {
        let r = cmd(con, "status")?;
        let got = numbers(&r, "volts", "status")?;
        let there = got.iter().zip(volts).all(|(g, v)| (g - v).abs() <= 0.5 + 1e-4 * v.abs());
        if there {
            return Ok(Driven {
                force: numbers(&r, "force", "status")?.first().copied().unwrap_or(f64::NAN),
                volts: got,
                joints_deg: numbers(&r, "joints", "status")?,
                tip: three(numbers(&r, "tip", "status")?, "tip")?,
                cable_mm: numbers(&r, "cable", "status")?.first().copied().unwrap_or(f64::NAN),
                readback: Readback::of(&r),
            });
        }
        if Instant::now() > deadline {
            return Err(RunError::Board(format!("the channels did not reach {volts:?} V (at {got:?} V)")));
        }
        cmd(con, "wait 0.05")?;
    }
}

/// The host's f64 model run of `scene` (without its continuum overlay): what the board is
/// compared with. Run it before a board is touched: a scene the model refuses never reaches one.
pub fn host(scene: &Scene) -> Result<SceneResult, RunError> {
    let mut s = scene.clone();
    s.output.reference = finger_scene::Reference::None;
    finger_scene::run(&s, None).map_err(RunError::Scene)
}

/// `scene` in another orientation (`finger run --grav --grav-dir`): gravity's magnitude (m/s²)
/// and direction (degrees from the straight finger's axis toward the cable side) of its finger,
/// each checked as the scene's own keys are; `None` keeps the scene's.
pub fn oriented(mut scene: Scene, grav: Option<f64>, grav_dir: Option<f64>) -> Result<Scene, RunError> {
    for (name, flag, v) in [("grav", "--grav", grav), ("grav_dir", "--grav-dir", grav_dir)] {
        if let Some(v) = v {
            scene.finger.params.set(name, v).map_err(|e| RunError::Scene(SceneError::model(finger_scene::Pos::WHOLE, flag, e)))?;
        }
    }
    Ok(scene)
}

/// Run the scene of `host` (see [`host`]) on the board: every posture through `solve`, and
/// with `drive` through `volt`/`force` as well, `stop` at the end whatever happened.
/// `progress` is told after each posture.
pub fn run(con: &mut Console, host: SceneResult, drive: bool, mut progress: impl FnMut(usize, usize)) -> Result<BoardRun, RunError> {
    let scene = host.scene.clone();
    if host.n != 3 {
        return Err(RunError::Board(format!("the board has 3 joints; this scene's finger has {}", host.n)));
    }
    let todo: Vec<(f64, Vec<f64>)> = host.postures.iter().map(|p| (p.tension, p.volts.clone())).collect();
    // the [match] target is another finger: not this board's
    let todo: Vec<_> = todo.into_iter().zip(&host.postures).filter(|(_, p)| p.kind != Kind::MatchTarget).map(|(t, _)| t).collect();
    load_finger(con, &scene.finger.params)?;
    let mut has_shape = true;
    let mut board = Vec::new();
    for (i, (t, v)) in todo.iter().enumerate() {
        board.push(ask(con, *t, v, &mut has_shape)?);
        if !drive {
            progress(i + 1, todo.len());
        }
    }
    if drive {
        let slew = board_params(con)?.iter().find(|(n, _)| n == "slew").map_or(2000.0, |x| x.1);
        let driven = cmd(con, "arm").and_then(|_| {
            for (i, (t, v)) in todo.iter().enumerate() {
                board[i].driven = Some(drive_to(con, *t, v, slew)?);
                progress(i + 1, todo.len());
            }
            Ok(())
        });
        let stopped = con.command("stop").map_err(|error| RunError::Command { line: "stop".into(), error });
        driven?;
        stopped?;
    }
    Ok(BoardRun { host, board, drove: drive })
}

fn joined(v: &[f64]) -> Vec<String> {
    v.iter().map(|x| x.to_string()).collect()
}

/// One row per posture: the host's f64 model next to the board's `solve` (and, driven, its
/// `status`), with the differences (board minus host).
pub fn csv(r: &BoardRun) -> String {
    let n = 3;
    let mut head: Vec<String> = vec!["scene".into(), "tension_N".into()];
    head.extend((1..=n).map(|k| format!("volts{k}_V")));
    for who in ["host", "board"] {
        head.extend((1..=n).map(|k| format!("{who}_joint{k}_deg")));
        head.extend(["tip_x_mm", "tip_y_mm", "tip_deg", "cable_mm"].map(|c| format!("{who}_{c}")));
        head.extend((1..=n).map(|k| format!("{who}_thickness{k}_mm")));
    }
    head.extend((1..=n).map(|k| format!("diff_joint{k}_deg")));
    head.extend(["diff_tip_mm".into(), "diff_tip_deg".into(), "board_iters".into()]);
    // the read-back's columns when every driven posture has one
    let readback = r.drove && r.board.iter().all(|b| b.driven.as_ref().is_some_and(|d| d.readback.is_some()));
    if r.drove {
        head.push("driven_force_N".into());
        head.extend((1..=n).map(|k| format!("driven_volts{k}_V")));
        head.extend((1..=n).map(|k| format!("driven_joint{k}_deg")));
        head.extend(["driven_tip_x_mm", "driven_tip_y_mm", "driven_tip_deg", "driven_cable_mm"].map(String::from));
    }
    if readback {
        head.extend((1..=n).map(|k| format!("driven_vmeas{k}_V")));
        head.extend((1..=n).map(|k| format!("driven_imeas{k}_uA")));
        head.extend((1..=n).map(|k| format!("driven_thick_meas{k}_mm")));
    }
    let mut out = head.join(",") + "\n";
    let hosts = r.host.postures.iter().filter(|p| p.kind != Kind::MatchTarget);
    for (h, b) in hosts.zip(&r.board) {
        let hj: Vec<f64> = h.joint_angles().iter().map(|a| a.to_degrees()).collect();
        let ht = h.tip();
        let mut row = vec![r.host.scene.name.clone(), h.tension.to_string()];
        row.extend(joined(&h.volts));
        row.extend(joined(&hj));
        row.extend(joined(&[ht.x, ht.y, ht.theta.to_degrees(), h.solution.cable_excursion]));
        row.extend(joined(&h.thickness));
        row.extend(joined(&b.joints_deg));
        row.extend(joined(&[b.tip[0], b.tip[1], b.tip[2], b.cable_mm]));
        row.extend(joined(&b.thick_mm));
        row.extend(b.joints_deg.iter().zip(&hj).map(|(x, y)| (x - y).to_string()));
        let dtip = ((b.tip[0] - ht.x).powi(2) + (b.tip[1] - ht.y).powi(2)).sqrt();
        row.extend(joined(&[dtip, b.tip[2] - ht.theta.to_degrees(), b.iters]));
        if let Some(d) = &b.driven {
            row.push(d.force.to_string());
            row.extend(joined(&d.volts));
            row.extend(joined(&d.joints_deg));
            row.extend(joined(&[d.tip[0], d.tip[1], d.tip[2], d.cable_mm]));
            if let (true, Some(rb)) = (readback, &d.readback) {
                row.extend(joined(&rb.vmeas_v));
                row.extend(joined(&rb.imeas_ua));
                row.extend(joined(&rb.thick_meas_mm));
            }
        }
        out += &(row.join(",") + "\n");
    }
    out
}

/// The host's postures (solid) with the board's (dashed: `shape`'s centreline, or a ring at
/// `solve`'s tip on a board without `shape`), in one plot.
pub fn svg(r: &BoardRun) -> String {
    let mut res = r.host.clone();
    res.postures.retain(|p| p.kind != Kind::MatchTarget);
    for (p, b) in res.postures.iter_mut().zip(&r.board) {
        p.reference = Some(RefPosture {
            points: b.points.clone().unwrap_or_else(|| vec![[b.tip[0], b.tip[1]]]),
            joint_angles: b.joints_deg.iter().map(|d| d.to_radians()).collect(),
            tip: Pose { x: b.tip[0], y: b.tip[1], theta: b.tip[2].to_radians() },
        });
    }
    res.scene.title = format!("{} (board vs host model)", res.scene.title);
    let what = if r.board.iter().all(|b| b.points.is_some()) { "board (shape)" } else { "board tip (solve)" };
    finger_scene::svg::plot_overlay(&res, what)
}
