//! The command side's state and dispatch: [`Commands`] (console lines in, replies and
//! [`Setpoints`] out), the ceilings, the servo plan, `arm` and `wait`; the handlers of the
//! commands that move or read the outputs and the model (`status`, `limits`, `solve`, `volt`,
//! `force`, `param`, `preset`, `cal`) are `handlers`'. `pose` and `contact` are `super::pose`'s,
//! `shape` `super::shape`'s, `save`/`config`/`factory` `super::config`'s; the finger, fmax
//! and the branch table `super::planner`'s.
//!
//! Safety rules, each in one place:
//! - The ceiling per channel, `vmax = min(board hold ceiling, the model's ceiling at its
//!   parameters, HV full scale, HV limit)`, and its duty are recomputed by
//!   [`Commands::recompute`], called on every parameter change.
//! - The outputs belong to the control core ([`crate::control::Control`]); the command side
//!   plans [`Setpoints`]; the core takes them unless a stop came meanwhile.
//! - A request at or past the ceiling is `err limit` and changes nothing: every command checks
//!   everything first and changes state only when all checks passed. Comparisons are written
//!   so that NaN fails them.
//! - `stop` is acted on where the bytes arrive ([`crate::rx`]), not here.

use core::fmt::Write;

use finger_model::{Calibration, Error as ModelError, Finger, Params};

use super::errors::{head, model_err, no_args, number, CmdError, ErrorCode};
use super::film;
use super::help::{Reply, DEG, HELP};
use super::params::{default_finger, FwParams, CHANNELS};
use super::planner::Planner;
use super::solves::{forward, Solved};
#[cfg(feature = "settings")]
use super::stored::ConfigState;
use crate::board::HV_MAX_V;
use crate::console;
use crate::control::{hv_duty_for, Setpoints, View};
use crate::num::{Fixed, Short};
use crate::rx::Record;
use finger_protocol::{const_concat, field, Command};

mod handlers;

/// Longest `wait`, s.
const WAIT_MAX_S: f32 = 600.0;

/// A running `wait`: start (control ms), length (ms), length as asked (s).
#[derive(Clone, Copy)]
pub(super) struct Wait {
    start_ms: u32,
    ms: u32,
    s: f32,
}

/// What `timing` reports: the runtime's own measurements (the chip's; the host has none).
pub trait TimingReport {
    fn write_timing(&mut self, out: &mut dyn Write);
}

/// The command side: console lines in, replies and [`Setpoints`] out. Owns no output; runs
/// at the lowest priority on the chip (RTIC's idle), inside [`super::App`] on the host.
pub struct Commands {
    /// The finger and what is kept from it: fmax, the branch table (app/planner.rs).
    pub(super) planner: Planner,
    /// The board's film: its law, hold ceiling, settling (app/film.rs).
    pub(super) film: film::BoardFilm,
    pub(super) fw: FwParams,
    pub(super) board_name: &'static str,
    pub(super) nl: &'static str,
    /// Full-scale duty of each HV PWM and of the servo PWM.
    pub(super) hv_max: [u16; CHANNELS],
    pub(super) servo_max: u16,
    pub(super) armed: bool,
    /// From the control core's [`View`]: HV enable, slewed values, duties, fault, time.
    pub(super) enable: bool,
    pub(super) volts: [f32; CHANNELS],
    pub(super) duty: [u16; CHANNELS],
    /// Each stack's thickness stretch now, as the control tick integrates it (1 at rest).
    pub(super) stack_ratio: [f32; CHANNELS],
    /// The read-back, on a board that has one.
    #[cfg(not(m3))]
    pub(super) sense: Option<crate::control::SenseView>,
    pub(super) trip_max_us: Option<u32>,
    /// The plant's truth (boards with a plant) and the request of the last `plant` line.
    #[cfg(not(feature = "hw"))]
    pub(super) plant_view: Option<crate::control::PlantView>,
    #[cfg(not(feature = "hw"))]
    pub(super) plant_req: Option<crate::control::PlantRequest>,
    /// The read-back's calibration in force, and a change not yet handed to the core.
    #[cfg(not(m3))]
    pub(super) sense_cal: super::hv_cal::SenseCal,
    #[cfg(not(m3))]
    pub(super) sense_cal_req: Option<super::hv_cal::SenseCal>,
    /// The core's latched fault, as the console names it, and the channel (0-based) whose
    /// read-back latched it.
    pub(super) fault: Option<&'static str>,
    pub(super) fault_ch: Option<u8>,
    pub(super) locked_out: bool,
    pub(super) now_ms: u32,
    /// HV setpoints (targets), V.
    pub(super) target_v: [f32; CHANNELS],
    /// Ceiling per channel, V, and its duty.
    pub(super) vmax: [f32; CHANNELS],
    pub(super) duty_max: [u16; CHANNELS],
    /// Cable tension target, N; the excursion and servo angle it gives.
    pub(super) force: f32,
    pub(super) cable: f32,
    pub(super) servo_deg: f32,
    /// Stops seen, setpoints sent.
    pub(super) epoch: u32,
    pub(super) seq: u32,
    pub(super) wait: Option<Wait>,
    /// A `stop` line reached [`Commands::execute`] (see [`Commands::take_stop`]).
    pub(super) stop_asked: bool,
    /// A `reset` was answered: the chip's command task reboots (see [`Commands::take_reset`]).
    #[cfg(all(target_os = "none", not(m3)))]
    pub(super) reset_asked: bool,
    /// The settings store and what the boot found in it (app/stored.rs, app/config.rs).
    #[cfg(feature = "settings")]
    pub(super) cfg: ConfigState,
}

impl Commands {
    /// Default parameters, disarmed. `board_name` and `nl` (line ending) from the board,
    /// `hv_max` / `servo_max` its PWMs' full-scale duties.
    pub fn new(board_name: &'static str, nl: &'static str, hv_max: [u16; CHANNELS], servo_max: u16) -> Self {
        let film = film::BoardFilm::new();
        let mut c = Commands {
            planner: Planner::new(default_finger(), board_cap_of(&film)),
            film,
            fw: FwParams::default(),
            board_name,
            nl,
            hv_max,
            servo_max,
            armed: false,
            enable: false,
            volts: [0.0; CHANNELS],
            duty: [0; CHANNELS],
            stack_ratio: [1.0; CHANNELS],
            #[cfg(not(m3))]
            sense: None,
            trip_max_us: None,
            #[cfg(not(feature = "hw"))]
            plant_view: None,
            #[cfg(not(feature = "hw"))]
            plant_req: None,
            #[cfg(not(m3))]
            sense_cal: super::hv_cal::SenseCal::NOMINAL,
            #[cfg(not(m3))]
            sense_cal_req: None,
            fault: None,
            fault_ch: None,
            locked_out: false,
            now_ms: 0,
            target_v: [0.0; CHANNELS],
            vmax: [0.0; CHANNELS],
            duty_max: [0; CHANNELS],
            force: 0.0,
            cable: 0.0,
            servo_deg: 0.0,
            epoch: 0,
            seq: 0,
            wait: None,
            stop_asked: false,
            #[cfg(all(target_os = "none", not(m3)))]
            reset_asked: false,
            #[cfg(feature = "settings")]
            cfg: ConfigState::new(),
        };
        c.recompute();
        c
    }

    pub fn finger(&self) -> &Finger<f32> {
        self.planner.finger()
    }
    pub fn fw_params(&self) -> &FwParams {
        &self.fw
    }
    pub fn armed(&self) -> bool {
        self.armed
    }
    pub fn targets(&self) -> [f32; CHANNELS] {
        self.target_v
    }
    /// Ceiling per channel, V.
    pub fn vmax(&self) -> [f32; CHANNELS] {
        self.vmax
    }
    /// The duty of each channel's ceiling.
    pub fn duty_ceiling(&self) -> [u16; CHANNELS] {
        self.duty_max
    }
    /// The line ending of the replies.
    pub fn newline(&self) -> &'static str {
        self.nl
    }
    /// A `wait` is running: no line is taken until it ends ([`Commands::poll_wait`]).
    pub fn busy(&self) -> bool {
        self.wait.is_some()
    }

    /// `err fault` for a latched fault `f`, naming its channel when one latched it.
    pub(in crate::app) fn latched(&self, f: &str) -> CmdError {
        match self.fault_ch {
            Some(k) => err!(Fault; "fault ", f, " latched on channel ", k + 1, "; send stop to clear it"),
            None => err!(Fault; "fault ", f, " latched; send stop to clear it"),
        }
    }

    /// Take the control core's report. A stop since the last one (a new epoch): disarmed,
    /// tension 0, targets 0, as the core already is.
    pub fn sync(&mut self, v: &View) {
        self.enable = v.enable;
        self.volts = v.volts;
        self.duty = v.duty;
        self.fault = v.fault.text();
        self.fault_ch = v.fault_ch;
        self.locked_out = v.locked_out;
        self.stack_ratio = v.stack_ratio;
        #[cfg(not(m3))]
        {
            self.sense = v.sense;
        }
        self.trip_max_us = v.trip_max_us;
        #[cfg(not(feature = "hw"))]
        {
            self.plant_view = v.plant;
        }
        self.now_ms = v.now_ms;
        if v.epoch != self.epoch {
            self.epoch = v.epoch;
            self.armed = false;
            self.force = 0.0;
            self.cable = 0.0;
            self.servo_deg = 0.0;
            self.target_v = [0.0; CHANNELS];
        }
    }

    /// A `stop` was executed as a line: the caller stops the control core.
    pub fn take_stop(&mut self) -> bool {
        core::mem::take(&mut self.stop_asked)
    }

    /// A `reset` was answered: the caller sends the reply, then reboots the chip.
    #[cfg(all(target_os = "none", not(m3)))]
    pub fn take_reset(&mut self) -> bool {
        core::mem::take(&mut self.reset_asked)
    }

    /// What the outputs should do now (a new `seq` each call).
    pub fn setpoints(&mut self) -> Setpoints {
        self.seq = self.seq.wrapping_add(1);
        Setpoints {
            seq: self.seq,
            epoch: self.epoch,
            armed: self.armed,
            target_v: self.target_v,
            servo_duty: self.servo_duty(self.servo_deg),
            servo_released: self.servo_duty(0.0),
            duty_ceiling: self.duty_max,
            slew: self.fw.slew,
            shaped: self.fw.shaped,
        }
    }

    /// Run one queued line; its reply (or, for `wait`, nothing yet) goes to `out`.
    pub fn run<W: Write>(&mut self, rec: Record, out: &mut W) {
        self.run_reporting(rec, out, None)
    }

    /// [`Commands::run`], with `timing` answered by the runtime's `report`.
    pub fn run_reporting<W: Write>(&mut self, rec: Record, out: &mut W, report: Option<&mut dyn TimingReport>) {
        let nl = self.nl;
        match rec {
            Record::Line(l) => self.execute_reporting(&l, out, report),
            Record::TooLong => {
                head(out, ErrorCode::TooLong);
                let _ = w!(out; "line longer than ", console::LINE_MAX, " bytes discarded", nl);
            }
            Record::Overrun(n) => {
                for _ in 0..n {
                    head(out, ErrorCode::Overrun);
                    let _ = w!(out; "bytes lost while receiving (line discarded); send it again", nl);
                }
            }
            Record::Stopped(n) => {
                for _ in 0..n {
                    head(out, ErrorCode::Stopped);
                    let _ = w!(out; "not run, a stop came after it", nl);
                }
            }
        }
    }

    /// A running `wait` ends when its time is up, or early when input arrived (`input`);
    /// writes its reply `ok waited=<s>` (early: `ok waited=<s elapsed> early=input`). True
    /// when it ended.
    pub fn poll_wait<W: Write>(&mut self, input: bool, out: &mut W) -> bool {
        let Some(w) = self.wait else { return false };
        let nl = self.nl;
        let el = self.now_ms.wrapping_sub(w.start_ms);
        if el >= w.ms {
            let _ = w!(out; const_concat!("ok ", field::WAITED.first()), Short(w.s), nl);
        } else if input {
            let _ = w!(out; const_concat!("ok ", field::WAITED.first()), Short(el as f32 / 1000.0), const_concat!(field::EARLY.after(), "input"), nl);
        } else {
            return false;
        }
        self.wait = None;
        true
    }

    // ---------------------------------------------------------------- ceilings, servo

    /// What the board allows whatever the model's parameters: min(the board's hold ceiling,
    /// the HV modules' full scale and limit), V. The model's ceiling in force takes it as its
    /// `hv_fs` term (`Finger::ceiling_in_force`), so the inverse and the board agree.
    pub(super) fn board_cap(&self) -> f32 {
        board_cap_of(&self.film)
    }

    /// The ceilings: per channel `min(board hold ceiling, the model's ceiling, HV full scale,
    /// HV limit)` and the duty it gives. Called on every parameter change.
    pub(super) fn recompute(&mut self) {
        // min(the model's ceiling, the board's hold ceiling, the modules' full scale and limit); NaN-proof
        let v = self.planner.finger().ceiling_in_force(Some(self.board_cap()));
        let v = if v >= 0.0 { v } else { 0.0 };
        let v = v.min(self.board_cap());
        // the inverse's branch table is built for the ceiling in force
        self.planner.clear_table();
        for ch in 0..CHANNELS {
            self.vmax[ch] = v;
            self.duty_max[ch] = hv_duty_for(v, self.hv_max[ch]);
        }
    }

    /// Servo duty for `deg` (0 = cable released): 1.0..2.0 ms over `servo_range`.
    pub(super) fn servo_duty(&self, deg: f32) -> u16 {
        let max = self.servo_max as f32;
        let frac = deg / self.fw.servo_range;
        let frac = if frac > 0.0 { frac.min(1.0) } else { 0.0 };
        let pulse_ms = if self.fw.servo_dir > 0.0 { 1.0 + frac } else { 2.0 - frac };
        (pulse_ms / 20.0 * max) as u16
    }

    /// Servo target `deg` (the control core moves it as the voltages slew).
    pub(super) fn set_servo(&mut self, deg: f32) {
        self.servo_deg = deg;
    }
    #[inline(never)]
    pub(super) fn plan_servo(&self, finger: &Finger<f32>, fw: &FwParams, force: f32, volts: &[f32; CHANNELS]) -> Result<(f32, f32), CmdError> {
        if force == 0.0 {
            return Ok((0.0, 0.0));
        }
        let excursion = |s: &Solved| s.cable_excursion;
        let cable = if core::ptr::eq(finger, self.planner.finger()) {
            self.planner.forward_with(force, volts, excursion)
        } else {
            forward(finger, force, volts).map(|s| excursion(&s))
        };
        let cable = cable.map_err(model_err)?.max(0.0);
        let deg = cable / fw.spool_r * DEG;
        if !(deg <= fw.servo_range) {
            return Err(
                err!(Limit; "cable excursion ", Fixed(cable, 2), " mm needs ", Fixed(deg, 1), " deg, past the servo travel ", Fixed(fw.servo_range, 0), " deg"),
            );
        }
        Ok((cable, deg))
    }

    /// How many times `Finger::fmax` ran (the cache's misses), for the tests.
    pub fn fmax_evaluations(&self) -> u32 {
        self.planner.fmax_evaluations()
    }

    /// The finger of `p` with calibration `cal` as the model (`param`, `preset`, `cal`): the
    /// servo plan of the present force and setpoints on it, then the ceilings. Refused, nothing
    /// changes.
    #[inline(never)]
    pub(super) fn adopt_model(&mut self, p: Params<f32>, cal: Calibration<f32>) -> Result<(), CmdError> {
        let f = Finger::with_calibration(p, cal).map_err(model_err)?;
        let (cable, deg) = self.plan_servo(&f, &self.fw, self.force, &self.target_v)?;
        self.planner.set_finger(f);
        self.cable = cable;
        self.set_servo(deg);
        self.recompute();
        Ok(())
    }

    /// The checks every setpoint change passes (`volt`, `force`, an armed `pose`), after
    /// the caller checked new voltages against the ceilings ([`Commands::check_volts`]): the
    /// tension at most fmax at those setpoints (nothing past the end of the branch),
    /// the servo within its travel. Nothing moves; returns where the servo must go
    /// (excursion mm, deg).
    #[inline(never)]
    pub(super) fn plan_setpoints(&self, force: f32, volts: &[f32; CHANNELS]) -> Result<(f32, f32), CmdError> {
        if force > 0.0 {
            let end = self.planner.fmax(volts).map_err(model_err)?;
            if !(force <= end.tension) {
                return Err(model_err(ModelError::ForceLimit { tension: force.into(), fmax: end.tension.into() }));
            }
        }
        self.plan_servo(self.planner.finger(), &self.fw, force, volts)
    }

    // ---------------------------------------------------------------- console
    /// Run one line (without terminator); writes exactly one final reply line (none for a
    /// blank line, and for `wait` the reply comes from `tick` when the time is up).
    pub fn execute<W: Write>(&mut self, line: &[u8], out: &mut W) {
        self.execute_reporting(line, out, None)
    }

    fn execute_reporting<W: Write>(&mut self, line: &[u8], out: &mut W, report: Option<&mut dyn TimingReport>) {
        let nl = self.nl;
        let toks = match console::tokens(line) {
            Some(t) => t,
            None => {
                head(out, ErrorCode::Usage);
                let _ = w!(out; "too many arguments", nl);
                return;
            }
        };
        if toks.is_empty() {
            return;
        }
        let mut reply = Reply::new();
        let r = self.dispatch(&toks, &mut reply, out, report);
        match r {
            Ok(true) => {}
            Ok(false) => {
                let _ = finger_protocol::Reply::Ok(finger_protocol::reply::Fields::new(&reply)).emit(out);
                let _ = w!(out; nl);
            }
            Err(e) => {
                e.emit(out);
                let _ = w!(out; nl);
            }
        }
    }

    /// Ok(true): the reply is written already (pose, contact) or comes later (wait).
    pub(super) fn dispatch<W: Write>(&mut self, t: &[&[u8]], r: &mut Reply, out: &mut W, report: Option<&mut dyn TimingReport>) -> Result<bool, CmdError> {
        let args = &t[1..];
        match Command::parse(t[0]) {
            Some(Command::Help) => {
                no_args(args, "help")?;
                let nl = self.nl;
                for l in HELP {
                    let _ = w!(out; l, nl);
                }
                if report.is_some() {
                    let _ = w!(out; super::help::HELP_TIMING, nl);
                }
                #[cfg(not(feature = "hw"))]
                if self.plant_view.is_some() {
                    let _ = w!(out; super::help::HELP_PLANT, nl);
                }
            }
            Some(Command::Version) => {
                no_args(args, "version")?;
                let _ = w!(r; field::VERSION.first(), crate::VERSION, field::NAME.after(), crate::NAME, field::BOARD.after(), self.board_name);
            }
            Some(Command::Status) => {
                no_args(args, "status")?;
                self.cmd_status(r);
            }
            Some(Command::Limits) => {
                no_args(args, "limits")?;
                self.cmd_limits(r);
            }
            #[cfg(not(m3))]
            Some(Command::Material) => {
                no_args(args, "material")?;
                self.film.write_material(r);
            }
            Some(Command::Solve) => self.cmd_solve(args, r)?,
            #[cfg(feature = "shape")]
            Some(Command::Shape) => self.cmd_shape(args, r)?,
            Some(Command::Arm) => {
                no_args(args, "arm")?;
                if let (true, Some(f)) = (self.locked_out, self.fault) {
                    return Err(err!(Fault; f, ": this image never arms here"));
                }
                if let Some(f) = self.fault {
                    return Err(self.latched(f));
                }
                self.armed = true;
                let _ = w!(r; const_concat!(field::ARMED.first(), "1"));
            }
            Some(Command::Disarm) => {
                no_args(args, "disarm")?;
                self.cmd_disarm()?;
                let _ = w!(r; const_concat!(field::ARMED.first(), "0"));
            }
            Some(Command::Stop) => {
                // reached only when a line is executed directly (App::execute): the RX part
                // acts on `stop` lines before they are queued
                self.stop_asked = true;
                let _ = w!(r; "stopped");
            }
            Some(Command::Timing) => {
                no_args(args, "timing")?;
                let Some(f) = report else { return Err(err!(Unknown; "timing is not in this build")) };
                f.write_timing(r);
            }
            Some(Command::Volt) => self.cmd_volt(args, r)?,
            Some(Command::Force) => self.cmd_force(args, r)?,
            #[cfg(feature = "pose")]
            Some(Command::Pose) => {
                self.cmd_pose(args, out)?;
                return Ok(true);
            }
            #[cfg(feature = "contact")]
            Some(Command::Contact) => {
                self.cmd_contact(args, out)?;
                return Ok(true);
            }
            #[cfg(m3)]
            Some(Command::Pose) => self.cmd_pose(args, r)?,
            #[cfg(not(any(feature = "pose", m3)))]
            Some(Command::Pose) => return Err(err!(Unknown; "pose is not in this build (feature pose)")),
            #[cfg(not(feature = "contact"))]
            Some(Command::Contact) => return Err(err!(Unknown; "contact is not in this build (feature contact)")),
            #[cfg(not(feature = "hw"))]
            Some(Command::Plant) => self.cmd_plant(args, r)?,
            #[cfg(feature = "hw")]
            Some(Command::Plant) => return Err(err!(Unknown; "plant is not in this build (the simulated plant: finger-sim and the emulator image)")),
            Some(Command::Param) => self.cmd_param(args, r, out)?,
            Some(Command::Preset) => self.cmd_preset(args, r)?,
            Some(Command::Cal) => self.cmd_cal(args, r)?,
            #[cfg(feature = "settings")]
            Some(Command::Save) => self.cmd_save(args, r)?,
            #[cfg(feature = "settings")]
            Some(Command::Factory) => self.cmd_factory(args, r)?,
            #[cfg(feature = "settings")]
            Some(Command::Config) => self.cmd_config(args, r, out)?,
            // a reboot from the console (the chip images): disarmed and the HV at 0 only
            #[cfg(all(target_os = "none", not(m3)))]
            Some(Command::Reset) => {
                no_args(args, "reset")?;
                self.require_disarmed("reset")?;
                self.reset_asked = true;
                let _ = w!(r; const_concat!(field::RESET.first(), "1"));
            }
            #[cfg(not(target_os = "none"))]
            Some(Command::Reset) => return Err(err!(Unknown; "reset reboots the chip images only; here, start the board again")),
            Some(Command::Wait) => {
                let [s] = args else { return Err(err!(Usage; "wait <seconds>")) };
                let s = number(s, "seconds")?;
                if !(0.0..=WAIT_MAX_S).contains(&s) {
                    return Err(err!(Usage; "wait: 0..", Short(WAIT_MAX_S), " s"));
                }
                let ms = (s * 1000.0 + 0.5) as u32;
                if ms == 0 {
                    let _ = w!(r; const_concat!(field::WAITED.first(), "0"));
                    return Ok(false);
                }
                self.wait = Some(Wait { start_ms: self.now_ms, ms, s });
                return Ok(true);
            }
            // a word no command has, or a command this build does not have
            _ => {
                return Err(err!(Unknown; "unknown command ", (console::printable(t[0])), "; try help"));
            }
        }
        Ok(false)
    }
}

/// The largest multiple of 0.1 V below `vmax` (V; 0 for a ceiling of 0.1 V or less): what
/// `limits`' `vmax_ok` reports, the highest voltage of a reply's precision `volt` accepts (not
/// in the M3 image: its flash).
#[cfg(not(m3))]
pub(crate) fn largest_below(vmax: f32) -> f32 {
    if !(vmax > 0.1) {
        return 0.0;
    }
    let mut tenths = (vmax * 10.0) as u32;
    if tenths as f32 / 10.0 >= vmax {
        tenths -= 1;
    }
    tenths as f32 / 10.0
}

/// [`Commands::board_cap`] of the board's film, V (the planner's `hv_fs` takes it at start).
fn board_cap_of(film: &film::BoardFilm) -> f32 {
    film.hold_ceiling().min(HV_MAX_V)
}
