//! The application: every command of shared/CONSOLE.md, the HV ceilings and the control loop.
//!
//! Safety rules, each in one place:
//! - The ceiling per channel, `vmax = min(margin x V_pi, v_supply, hv_fs)`, and its duty are
//!   recomputed by [`App::recompute`], called on every parameter change.
//! - [`App::write_hv_duty`] is the only code that writes an HV duty; it refuses any duty above
//!   the ceiling's duty, whoever calls it, and latches the fault `hv-refused`.
//! - A request at or past the ceiling is `err limit` and changes nothing: every command checks
//!   everything first and changes state only when all checks passed.
//! - The HV setpoints move at `slew` V/s in [`App::tick`], the control loop, which alone feeds
//!   the watchdog. `disarm` ramps to 0, then drops the enable; `stop` zeroes the duties and
//!   drops the enable at once, releases the cable and disarms.
//! - The HV enable is low from [`App::new`] until `arm`.

use core::cell::Cell;
use core::fmt::Write;

use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;
use finger_model::params::PARAMS;
use finger_model::{BranchLimit, Error as ModelError, Finger, Method, Params, Solution};
use heapless::String;

use crate::board::{Board, HV_CHANNELS};
use crate::console::{self, Line, LineBuf, NumError};
use crate::num::{self, Exp, Fixed, List, Short};
use crate::out::Emit;

/// `err!(code; pieces...)`: a console error with a message written from pieces
/// ([`crate::out::Emit`]).
macro_rules! err {
    ($code:expr; $($x:expr),+ $(,)?) => {{
        let mut msg: String<160> = String::new();
        let _ = w!(&mut msg; $($x),+);
        CmdError { code: $code, msg }
    }};
}

/// Number of HV channels / joints the board drives.
pub const CHANNELS: usize = HV_CHANNELS;

const DEG: f32 = 180.0 / core::f32::consts::PI;
/// Longest `wait`, s.
const WAIT_MAX_S: f32 = 600.0;

/// Firmware-only parameters (not in the model).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FwParams {
    /// HV setpoint slew rate, V/s.
    pub slew: f32,
    /// Servo spool radius, mm: servo angle = cable excursion / spool_r.
    pub spool_r: f32,
    /// Servo travel for pulses 1.0..2.0 ms, degrees.
    pub servo_range: f32,
    /// Servo direction: +1 (cable pulled in as the pulse grows from 1.0 ms) or -1.
    pub servo_dir: f32,
    /// HV calibration: module output at 100 % control duty (5 V control input), V.
    pub hv_fs: f32,
    /// HV calibration: control duty that gives 0 V, percent.
    pub hv_zero: f32,
}

impl Default for FwParams {
    fn default() -> Self {
        FwParams { slew: 2000.0, spool_r: 10.0, servo_range: 180.0, servo_dir: 1.0, hv_fs: 10_000.0, hv_zero: 0.0 }
    }
}

/// A firmware parameter's name and range (as the console reports it).
pub struct FwParamInfo {
    pub name: &'static str,
    pub min: f32,
    pub max: f32,
    pub range: &'static str,
}

pub const FW_PARAMS: &[FwParamInfo] = &[
    FwParamInfo { name: "slew", min: 1.0, max: 1e5, range: "1..1e5 V/s" },
    FwParamInfo { name: "spool_r", min: 0.5, max: 100.0, range: "0.5..100 mm" },
    FwParamInfo { name: "servo_range", min: 10.0, max: 360.0, range: "10..360 deg (1.0..2.0 ms)" },
    FwParamInfo { name: "servo_dir", min: -1.0, max: 1.0, range: "1 or -1" },
    FwParamInfo { name: "hv_fs", min: 100.0, max: 1e5, range: "100..1e5 V at 100 % duty" },
    FwParamInfo { name: "hv_zero", min: 0.0, max: 50.0, range: "0..50 % duty at 0 V" },
];

impl FwParams {
    pub fn get(&self, name: &str) -> Option<f32> {
        Some(match name {
            "slew" => self.slew,
            "spool_r" => self.spool_r,
            "servo_range" => self.servo_range,
            "servo_dir" => self.servo_dir,
            "hv_fs" => self.hv_fs,
            "hv_zero" => self.hv_zero,
            _ => return None,
        })
    }

    /// Set by name; on error nothing changes.
    fn set(&mut self, name: &str, v: f32) -> Result<(), CmdError> {
        let info = FW_PARAMS.iter().find(|i| i.name == name).ok_or_else(|| err!("unknown"; "no parameter ", name))?;
        let bad = || err!("usage"; "parameter ", info.name, " out of range: ", info.range);
        if !(v >= info.min && v <= info.max) {
            return Err(bad());
        }
        let f = v;
        match name {
            "slew" => self.slew = f,
            "spool_r" => self.spool_r = f,
            "servo_range" => self.servo_range = f,
            "servo_dir" if v == 1.0 || v == -1.0 => self.servo_dir = f,
            "hv_fs" => self.hv_fs = f,
            "hv_zero" => self.hv_zero = f,
            _ => return Err(bad()),
        }
        Ok(())
    }
}

/// A refused command: its code (CONSOLE.md) and a human message.
#[derive(Debug)]
pub struct CmdError {
    pub code: &'static str,
    pub msg: String<160>,
}

impl CmdError {
    /// A console error with a fixed message.
    pub fn new(code: &'static str, msg: &str) -> Self {
        let mut m = String::new();
        for c in msg.chars() {
            if m.push(c).is_err() {
                break;
            }
        }
        CmdError { code, msg: m }
    }
}

/// A model error as a console error: its code, and a message written from its fields by
/// [`num::write_model_error`] (never the model's `Display`: it links core's float formatting).
pub(crate) fn model_err(e: ModelError) -> CmdError {
    let mut msg = String::new();
    let _ = num::write_model_error(&mut msg, &e);
    CmdError { code: e.code(), msg }
}

/// The refusal of [`App::write_hv_duty`].
#[derive(Debug, PartialEq, Eq, Clone, Copy)]
pub struct HvRefused;

type Reply = String<400>;

/// The application on a board `B`.
pub struct App<B: Board> {
    board: B,
    finger: Finger<f32>,
    fw: FwParams,
    line: LineBuf,
    armed: bool,
    /// `disarm` given, HV still ramping down; the enable drops at 0.
    ramping_down: bool,
    enable: bool,
    /// HV setpoints (targets) and the slewed values now, V.
    target_v: [f32; CHANNELS],
    volts: [f32; CHANNELS],
    /// Duty written last per channel.
    duty: [u16; CHANNELS],
    /// Ceiling per channel, V, and its duty.
    vmax: [f32; CHANNELS],
    duty_max: [u16; CHANNELS],
    /// Full-scale duty of each HV PWM (read once from the board).
    hv_max: [u16; CHANNELS],
    /// Cable tension target, N; the excursion and servo angle it gives.
    force: f32,
    cable: f32,
    servo_deg: f32,
    fault: Option<&'static str>,
    /// Remaining time of a `wait`, ms, and its length for the reply.
    wait_ms: u32,
    wait_s: f32,
    /// Control-loop time, ms.
    now_ms: u64,
    /// `Finger::fmax` at the setpoints it was computed for ([`App::fmax`]), and how many
    /// times it was computed.
    fmax_cache: Cell<Option<([f32; CHANNELS], Result<BranchLimit<f32>, ModelError>)>>,
    fmax_computed: Cell<u32>,
    /// The inverse's branch table for the current model (`pose`), built at the first `pose`
    /// after a model change (1.18 M instructions for the default model, about 7 ms at
    /// 168 MHz; docs/inverse-cost.md) and cleared by [`App::set_finger`]. None also for a finger without stacks.
    #[cfg(feature = "pose")]
    inv_table: Option<finger_model::inverse::BranchTable<f32>>,
}

impl<B: Board> App<B> {
    /// Take the board: HV enable low, every HV duty 0, cable released. Default parameters.
    pub fn new(mut board: B) -> Self {
        let mut hv_max = [0u16; CHANNELS];
        for (ch, m) in hv_max.iter_mut().enumerate() {
            *m = board.hv(ch).max_duty_cycle();
        }
        // the defaults are valid (a model test); no Debug formatting of the error on the target
        let finger = match Finger::new(preset(Params::default())) {
            Ok(f) => f,
            Err(_) => panic!("default parameters"),
        };
        let mut app = App {
            board,
            finger,
            fw: FwParams::default(),
            line: LineBuf::new(),
            armed: false,
            ramping_down: false,
            enable: false,
            target_v: [0.0; CHANNELS],
            volts: [0.0; CHANNELS],
            duty: [0; CHANNELS],
            vmax: [0.0; CHANNELS],
            duty_max: [0; CHANNELS],
            hv_max,
            force: 0.0,
            cable: 0.0,
            servo_deg: 0.0,
            fault: None,
            wait_ms: 0,
            wait_s: 0.0,
            now_ms: 0,
            fmax_cache: Cell::new(None),
            fmax_computed: Cell::new(0),
            #[cfg(feature = "pose")]
            inv_table: None,
        };
        app.hv_off_now();
        app.recompute();
        app.set_servo(0.0);
        app
    }

    pub fn board(&self) -> &B {
        &self.board
    }
    pub fn board_mut(&mut self) -> &mut B {
        &mut self.board
    }
    pub fn finger(&self) -> &Finger<f32> {
        &self.finger
    }
    pub fn fw_params(&self) -> &FwParams {
        &self.fw
    }
    pub fn armed(&self) -> bool {
        self.armed
    }
    pub fn hv_enabled(&self) -> bool {
        self.enable
    }
    /// Slewed HV values now, V.
    pub fn volts(&self) -> [f32; CHANNELS] {
        self.volts
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
    pub fn duties(&self) -> [u16; CHANNELS] {
        self.duty
    }
    pub fn fault(&self) -> Option<&'static str> {
        self.fault
    }
    /// A `wait` is running: the caller keeps calling `tick` and sends no input until it ends.
    pub fn busy(&self) -> bool {
        self.wait_ms > 0
    }
    pub fn now_ms(&self) -> u64 {
        self.now_ms
    }

    // ---------------------------------------------------------------- outputs, safety

    /// The ceilings: per channel `min(margin x V_pi, v_supply, hv_fs)` and the duty it gives.
    /// Called on every parameter change.
    fn recompute(&mut self) {
        let v = self.finger.ceiling_in_force(Some(self.fw.hv_fs));
        // the inverse's branch table is built for the ceiling in force
        #[cfg(feature = "pose")]
        {
            self.inv_table = None;
        }
        for ch in 0..CHANNELS {
            self.vmax[ch] = v;
            self.duty_max[ch] = self.duty_for(ch, v);
        }
    }

    /// Control duty that makes channel `ch`'s module output `v` volts (linear calibration:
    /// duty% = hv_zero + (100 - hv_zero) v / hv_fs), rounded down.
    fn duty_for(&self, ch: usize, v: f32) -> u16 {
        let max = self.board_hv_max(ch) as f32;
        let z = self.fw.hv_zero / 100.0;
        let frac = z + (1.0 - z) * (v / self.fw.hv_fs);
        let d = frac * max;
        if !(d > 0.0) {
            0
        } else if d >= max {
            max as u16
        } else {
            d as u16
        }
    }

    fn board_hv_max(&self, ch: usize) -> u16 {
        self.hv_max[ch]
    }

    /// The one function that writes an HV duty. Refuses (writes nothing, latches the fault
    /// `hv-refused`) any duty above the channel's ceiling duty, whoever calls it.
    pub fn write_hv_duty(&mut self, ch: usize, duty: u16) -> Result<(), HvRefused> {
        if ch >= CHANNELS || duty > self.duty_max[ch] {
            self.fault = Some("hv-refused");
            return Err(HvRefused);
        }
        if self.board.hv(ch).set_duty_cycle(duty).is_err() {
            self.fault = Some("pwm");
            return Err(HvRefused);
        }
        self.duty[ch] = duty;
        Ok(())
    }

    fn set_enable(&mut self, on: bool) {
        let r = if on { self.board.hv_enable().set_high() } else { self.board.hv_enable().set_low() };
        if r.is_err() {
            self.fault = Some("enable");
        }
        self.enable = on && r.is_ok();
    }

    /// HV off at once: every duty 0, enable low, setpoints 0.
    fn hv_off_now(&mut self) {
        self.set_enable(false);
        for ch in 0..CHANNELS {
            let _ = self.write_hv_duty(ch, 0);
        }
        self.volts = [0.0; CHANNELS];
        self.target_v = [0.0; CHANNELS];
        self.ramping_down = false;
    }

    /// Servo to `deg` (0 = cable released).
    fn set_servo(&mut self, deg: f32) {
        let max = self.board.servo().max_duty_cycle() as f32;
        let frac = (deg / self.fw.servo_range).max(0.0).min(1.0);
        let pulse_ms = if self.fw.servo_dir > 0.0 { 1.0 + frac } else { 2.0 - frac };
        let duty = (pulse_ms / 20.0 * max) as u16;
        if self.board.servo().set_duty_cycle(duty).is_err() {
            self.fault = Some("pwm");
        }
        self.servo_deg = deg;
    }

    /// Where the servo must go to hold `force` at the HV setpoints `volts`: (excursion mm,
    /// servo deg). Checks the servo travel; nothing moves.
    #[inline(never)]
    fn plan_servo(&self, finger: &Finger<f32>, fw: &FwParams, force: f32, volts: &[f32; CHANNELS]) -> Result<(f32, f32), CmdError> {
        if force == 0.0 {
            return Ok((0.0, 0.0));
        }
        let sol = finger.solve(force, volts, Method::converged()).map_err(model_err)?;
        let cable = sol.cable_excursion.max(0.0);
        let deg = cable / fw.spool_r * DEG;
        if !(deg <= fw.servo_range) {
            return Err(err!("limit"; "cable excursion ", Fixed(cable, 2), " mm needs ", Fixed(deg, 1), " deg, past the servo travel ", Fixed(fw.servo_range, 0), " deg"));
        }
        Ok((cable, deg))
    }

    /// The end of the equilibrium branch at the HV setpoints `volts` (`Finger::fmax`),
    /// cached: computed once per model and set of setpoints (the cache is keyed by the
    /// setpoints and cleared when a parameter changes, [`App::set_finger`]).
    fn fmax(&self, volts: &[f32; CHANNELS]) -> Result<BranchLimit<f32>, ModelError> {
        if let Some((key, r)) = self.fmax_cache.get() {
            if key == *volts {
                return r;
            }
        }
        let r = self.finger.fmax(volts);
        self.fmax_cache.set(Some((*volts, r)));
        self.fmax_computed.set(self.fmax_computed.get() + 1);
        r
    }

    /// How many times `Finger::fmax` ran (the cache's misses), for the tests.
    pub fn fmax_evaluations(&self) -> u32 {
        self.fmax_computed.get()
    }

    /// The inverse's options on this board: its ceiling is the one in force (HV full scale too).
    #[cfg(feature = "pose")]
    fn inverse_options(&self) -> finger_model::inverse::Options<f32> {
        finger_model::inverse::Options { hv_fs: Some(self.fw.hv_fs), ..Default::default() }
    }

    /// A new model (parameter or preset change): the fmax cache no longer holds.
    fn set_finger(&mut self, f: Finger<f32>) {
        self.finger = f;
        self.fmax_cache.set(None);
        #[cfg(feature = "pose")]
        {
            self.inv_table = None;
        }
    }

    /// The checks every setpoint change passes (`volt`, `force`, an armed `pose`), after
    /// the caller checked new voltages against the ceilings ([`App::check_volts`]): the
    /// tension at most fmax at those setpoints (issue 7: nothing past the end of the branch),
    /// the servo within its travel. Nothing moves; returns where the servo must go
    /// (excursion mm, deg).
    #[inline(never)]
    fn plan_setpoints(&self, force: f32, volts: &[f32; CHANNELS]) -> Result<(f32, f32), CmdError> {
        if force > 0.0 {
            let end = self.fmax(volts).map_err(model_err)?;
            if force > end.tension {
                return Err(model_err(ModelError::ForceLimit { tension: force.into(), fmax: end.tension.into() }));
            }
        }
        self.plan_servo(&self.finger, &self.fw, force, volts)
    }

    /// Emergency stop: HV off at once, cable released, disarmed. Clears a latched fault.
    pub fn emergency_stop(&mut self) {
        self.hv_off_now();
        self.armed = false;
        self.force = 0.0;
        self.cable = 0.0;
        self.set_servo(0.0);
        self.wait_ms = 0;
        self.fault = None;
    }

    /// The control loop, every `dt_ms`: slews the HV values toward their setpoints, drops the
    /// enable once a disarm ramp reached 0, feeds the watchdog, finishes a `wait`.
    pub fn tick<W: Write>(&mut self, dt_ms: u32, out: &mut W) {
        self.now_ms += dt_ms as u64;
        let step = self.fw.slew * dt_ms as f32 / 1000.0;
        for ch in 0..CHANNELS {
            let (v, t) = (self.volts[ch], self.target_v[ch]);
            if v != t {
                let nv = if t > v { (v + step).min(t) } else { (v - step).max(t) };
                let d = self.duty_for(ch, nv);
                if self.write_hv_duty(ch, d).is_err() {
                    // cannot happen with targets below the ceiling; never go on
                    let f = self.fault;
                    self.emergency_stop();
                    self.fault = f;
                    break;
                }
                self.volts[ch] = nv;
            }
        }
        if self.ramping_down && self.volts.iter().all(|&v| v == 0.0) {
            for ch in 0..CHANNELS {
                let _ = self.write_hv_duty(ch, 0);
            }
            self.set_enable(false);
            self.ramping_down = false;
        }
        self.board.feed_watchdog();
        if self.wait_ms > 0 {
            self.wait_ms = self.wait_ms.saturating_sub(dt_ms);
            if self.wait_ms == 0 {
                let nl = self.board.newline();
                let _ = w!(out; "ok waited=", Short(self.wait_s), nl);
            }
        }
    }

    // ---------------------------------------------------------------- console

    /// Feed received bytes; replies go to `out`. Stop feeding while `busy()`.
    pub fn input<W: Write>(&mut self, bytes: &[u8], out: &mut W) {
        for &b in bytes {
            self.input_byte(b, out);
        }
    }

    pub fn input_byte<W: Write>(&mut self, b: u8, out: &mut W) {
        let mut copy: heapless::Vec<u8, { console::LINE_MAX }> = heapless::Vec::new();
        let too_long = match self.line.push(b) {
            None => return,
            Some(Line::TooLong) => true,
            Some(Line::Text(t)) => {
                let _ = copy.extend_from_slice(t);
                false
            }
        };
        let nl = self.board.newline();
        if too_long {
            let _ = w!(out; "err too-long: line longer than ", console::LINE_MAX, " bytes discarded", nl);
            return;
        }
        self.execute(&copy, out);
    }

    /// Run one line (without terminator); writes exactly one final reply line (none for a
    /// blank line, and for `wait` the reply comes from `tick` when the time is up).
    pub fn execute<W: Write>(&mut self, line: &[u8], out: &mut W) {
        let nl = self.board.newline();
        let toks = match console::tokens(line) {
            Some(t) => t,
            None => {
                let _ = w!(out; "err usage: too many arguments", nl);
                return;
            }
        };
        if toks.is_empty() {
            return;
        }
        let mut reply = Reply::new();
        let r = self.dispatch(&toks, &mut reply, out);
        match r {
            Ok(true) => {}
            Ok(false) => {
                let _ = if reply.is_empty() { w!(out; "ok", nl) } else { w!(out; "ok ", reply, nl) };
            }
            Err(e) => {
                let _ = w!(out; "err ", e.code, ": ", e.msg, nl);
            }
        }
    }

    /// Ok(true): the reply is written already (pose, contact) or comes later (wait).
    fn dispatch<W: Write>(&mut self, t: &[&[u8]], r: &mut Reply, out: &mut W) -> Result<bool, CmdError> {
        let args = &t[1..];
        match t[0] {
            b"help" => {
                no_args(args, "help")?;
                let nl = self.board.newline();
                for l in HELP {
                    let _ = w!(out; l, nl);
                }
            }
            b"version" => {
                no_args(args, "version")?;
                let _ = w!(r; "version=", crate::VERSION, " name=", crate::NAME, " board=", self.board.name());
            }
            b"status" => {
                no_args(args, "status")?;
                self.cmd_status(r);
            }
            b"limits" => {
                no_args(args, "limits")?;
                self.cmd_limits(r);
            }
            b"solve" => self.cmd_solve(args, r)?,
            b"arm" => {
                no_args(args, "arm")?;
                if let Some(f) = self.fault {
                    return Err(err!("fault"; "fault ", f, " latched; send stop to clear it"));
                }
                self.armed = true;
                self.ramping_down = false;
                self.set_enable(true);
                let _ = w!(r; "armed=1");
            }
            b"disarm" => {
                no_args(args, "disarm")?;
                self.cmd_disarm()?;
                let _ = w!(r; "armed=0");
            }
            b"stop" => {
                no_args(args, "stop")?;
                self.emergency_stop();
                let _ = w!(r; "stopped");
            }
            b"volt" => self.cmd_volt(args, r)?,
            b"force" => self.cmd_force(args, r)?,
            #[cfg(feature = "pose")]
            b"pose" => {
                self.cmd_pose(args, out)?;
                return Ok(true);
            }
            #[cfg(feature = "contact")]
            b"contact" => {
                self.cmd_contact(args, out)?;
                return Ok(true);
            }
            #[cfg(not(feature = "pose"))]
            b"pose" => return Err(err!("unknown"; "pose is not in this build (feature pose)")),
            #[cfg(not(feature = "contact"))]
            b"contact" => return Err(err!("unknown"; "contact is not in this build (feature contact)")),
            b"param" => self.cmd_param(args, r, out)?,
            b"preset" => self.cmd_preset(args, r)?,
            b"wait" => {
                let [s] = args else { return Err(err!("usage"; "wait <seconds>")) };
                let s = number(s, "seconds")?;
                if !(s >= 0.0 && s <= WAIT_MAX_S) {
                    return Err(err!("usage"; "wait: 0..", Short(WAIT_MAX_S), " s"));
                }
                let ms = (s * 1000.0 + 0.5) as u32;
                if ms == 0 {
                    let _ = w!(r; "waited=0");
                    return Ok(false);
                }
                self.wait_ms = ms;
                self.wait_s = s;
                return Ok(true);
            }
            w => {
                return Err(err!("unknown"; "unknown command ", (console::printable(w)), "; try help"));
            }
        }
        Ok(false)
    }

    #[inline(never)]
    fn cmd_status(&self, r: &mut Reply) {
        let _ = w!(r; "armed=", self.armed as u8, " force=", Fixed(self.force, 3), " volts=");
        list(r, &self.volts, 1);
        let mut thick = [0.0f32; CHANNELS];
        for ch in 0..CHANNELS {
            thick[ch] = self.finger.stack_thickness(self.volts[ch]).unwrap_or(0.0);
        }
        let _ = w!(r; " thick=");
        list(r, &thick, 4);
        let sol = self.finger.solve(self.force, &self.volts, Method::converged());
        let mut fault = self.fault;
        match sol {
            Ok(s) => {
                let _ = w!(r; " joints=");
                joints(r, &s);
                let tip = s.tip();
                let _ = w!(r; " tip=", Tip(&tip));
            }
            Err(_) => {
                let _ = w!(r; " joints=-,-,- tip=-,-,-");
                fault = fault.or(Some("model"));
            }
        }
        let _ = w!(r; " cable=", Fixed(self.cable, 3), " servo=", Fixed(self.servo_deg, 2), " fault=", fault.unwrap_or("none"));
        let _ = w!(r; " enable=", self.enable as u8, " target=");
        list(r, &self.target_v, 1);
    }

    #[inline(never)]
    fn cmd_limits(&self, r: &mut Reply) {
        let _ = w!(r; "vmax=");
        list(r, &self.vmax, 1);
        let p = self.finger.params();
        let _ = w!(r; " vpullin=", Fixed(self.finger.pull_in_voltage(), 1), " supply=", Fixed(p.v_supply, 1), " margin=", Short(p.margin));
        match self.fmax(&self.target_v) {
            Ok(b) => {
                let kind = match b.kind {
                    finger_model::BranchEnd::Contact => "contact",
                    finger_model::BranchEnd::LimitPoint => "limit-point",
                    finger_model::BranchEnd::SearchBound => "search-bound",
                };
                let _ = w!(r; " fmax=", Fixed(b.tension, 4), " fmax_end=", kind, ",", b.joint);
            }
            Err(_) => {
                let _ = w!(r; " fmax=- fmax_end=error");
            }
        }
        let _ = w!(r; " slew=", Short(self.fw.slew), " servo=0,", Short(self.fw.servo_range), " cable_max=", Fixed(self.fw.servo_range / DEG * self.fw.spool_r, 2), " dutymax=");
        let d = self.duty_max;
        let _ = w!(r; d[0], ",", d[1], ",", d[2]);
    }

    /// Check channel voltages against the ceilings: `limit` at or past.
    fn check_volts(&self, v: &[f32; CHANNELS]) -> Result<(), CmdError> {
        self.check_volts_of(v, false)
    }

    /// As [`App::check_volts`]; with `zero_is_off`, a channel at 0 V passes whatever its
    /// ceiling (a computed answer, such as `pose`'s on a finger without stacks).
    #[inline(never)]
    fn check_volts_of(&self, v: &[f32; CHANNELS], zero_is_off: bool) -> Result<(), CmdError> {
        for ch in 0..CHANNELS {
            if zero_is_off && v[ch] == 0.0 {
                continue;
            }
            if v[ch] < 0.0 {
                return Err(err!("usage"; "channel ", (ch + 1), ": voltage must be >= 0"));
            }
            if v[ch] >= self.vmax[ch] {
                return Err(err!("limit"; "channel ", (ch + 1), ": ", Fixed(v[ch], 1), " V is at or past the ceiling ", Fixed(self.vmax[ch], 1), " V (see limits)"));
            }
        }
        Ok(())
    }

    #[inline(never)]
    fn cmd_solve(&self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        // the voltages are optional on a finger without stacks (layers = 0); 0 V is off, never a request
        let v = match args {
            [_, v1, v2, v3] => [number(v1, "V1")?, number(v2, "V2")?, number(v3, "V3")?],
            [_] if self.finger.params().layers == 0 => [0.0; CHANNELS],
            _ => return Err(err!("usage"; "solve <P> <V1> <V2> <V3> (solve <P> without stacks)")),
        };
        let p = tension(number(args[0], "P")?)?;
        self.check_volts_of(&v, true)?;
        let vf = v.map(|x| x as f32);
        let sol = self.finger.solve(p, &vf, Method::converged()).map_err(model_err)?;
        let k = self.finger.tip_stiffness(&sol).map_err(model_err)?;
        let _ = w!(r; "joints=");
        joints(r, &sol);
        let tip = sol.tip();
        let _ = w!(r; " tip=", Tip(&tip), " cable=", Fixed(sol.cable_excursion, 4), " thick=");
        list(r, &sol.thickness[..CHANNELS], 4);
        let _ = w!(r; " stiffness=", Exp(k[0][0], 4), ",", Exp(k[1][1], 4), ",", Exp(k[2][2], 4), " iters=", sol.iterations);
        Ok(())
    }

    #[inline(never)]
    fn cmd_disarm(&mut self) -> Result<(), CmdError> {
        if !self.armed {
            return Ok(());
        }
        // the cable keeps its tension, held at the posture of 0 V; if that cannot be
        // held, the cable is released
        let zero = [0.0; CHANNELS];
        match self.plan_servo(&self.finger, &self.fw, self.force, &zero) {
            Ok((cable, deg)) => {
                self.cable = cable;
                self.set_servo(deg);
            }
            Err(_) => {
                self.force = 0.0;
                self.cable = 0.0;
                self.set_servo(0.0);
            }
        }
        self.armed = false;
        self.target_v = zero;
        self.ramping_down = true;
        if self.volts.iter().all(|&v| v == 0.0) {
            for ch in 0..CHANNELS {
                let _ = self.write_hv_duty(ch, 0);
            }
            self.set_enable(false);
            self.ramping_down = false;
        }
        Ok(())
    }

    #[inline(never)]
    fn cmd_volt(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        let [ch, v] = args else { return Err(err!("usage"; "volt <1|2|3|all> <V>")) };
        let chans: &[usize] = match *ch {
            b"1" => &[0],
            b"2" => &[1],
            b"3" => &[2],
            b"all" => &[0, 1, 2],
            c => return Err(err!("usage"; "volt: channel ", (console::printable(c)), " is not 1, 2, 3 or all")),
        };
        let v = number(v, "V")?;
        if v < 0.0 {
            return Err(err!("usage"; "volt: voltage must be >= 0"));
        }
        self.require_armed("volt")?;
        let mut req = self.target_v;
        for &c in chans {
            req[c] = v;
        }
        self.check_volts(&req)?;
        let target = req;
        let (cable, deg) = self.plan_setpoints(self.force, &target)?;
        self.target_v = target;
        self.cable = cable;
        self.set_servo(deg);
        let _ = w!(r; "volts=");
        list(r, &self.target_v, 1);
        Ok(())
    }

    fn require_armed(&self, what: &str) -> Result<(), CmdError> {
        if let Some(f) = self.fault {
            return Err(err!("fault"; "fault ", f, " latched; send stop to clear it"));
        }
        if !self.armed {
            return Err(err!("not-armed"; what, " needs arm"));
        }
        Ok(())
    }

    #[inline(never)]
    fn cmd_force(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        let [p] = args else { return Err(err!("usage"; "force <P>")) };
        let p = tension(number(p, "P")?)?;
        self.require_armed("force")?;
        let (cable, deg) = self.plan_setpoints(p, &self.target_v)?;
        self.force = p;
        self.cable = cable;
        self.set_servo(deg);
        let _ = w!(r; "force=", Fixed(self.force, 3), " cable=", Fixed(self.cable, 3), " servo=", Fixed(self.servo_deg, 2));
        Ok(())
    }

    #[cfg(feature = "pose")]
    /// `pose d1 d2 d3 [P]`: the inverse model (issue 4, [`crate::inverse_cmds::pose`]).
    /// Writes its reply line itself. Armed, the solution goes through the checks of `volt`
    /// and `force` ([`App::plan_setpoints`]) and then moves the outputs; disarmed it answers
    /// and moves nothing; refused or unreachable, nothing moves.
    #[inline(never)]
    fn cmd_pose<W: Write>(&mut self, args: &[&[u8]], out: &mut W) -> Result<(), CmdError> {
        if args.len() != 3 && args.len() != 4 {
            return Err(err!("usage"; "pose <d1> <d2> <d3> [<P>]"));
        }
        let mut deg = [0.0f32; CHANNELS];
        for ch in 0..CHANNELS {
            let d = number(args[ch], "angle")?;
            if !(d.abs() <= 360.0) {
                return Err(err!("usage"; "pose: joint angles are degrees, |d| <= 360"));
            }
            deg[ch] = d;
        }
        let p = match args.get(3) {
            Some(t) => Some(tension(number(t, "P")?)?),
            None => None,
        };
        if self.inv_table.is_none() && self.finger.params().layers > 0 {
            self.inv_table = finger_model::inverse::BranchTable::new(&self.finger, &self.inverse_options()).ok();
        }
        let armed = self.armed;
        let mut plan = None;
        let mut line: String<240> = String::new();
        let this = &*self;
        let _ = crate::inverse_cmds::pose_with(&mut line, &this.finger, this.inv_table.as_ref(), &this.inverse_options(), &deg, p, |t, v| {
            if !armed {
                return Ok(());
            }
            this.require_armed("pose")?;
            let target = [v[0], v[1], v[2]];
            // the ceilings as `volt` checks them; 0 V (a joint without stacks) is off, not a request
            this.check_volts_of(&target, true)?;
            let (cable, sdeg) = this.plan_setpoints(t, &target)?;
            plan = Some((t, target, cable, sdeg));
            Ok(())
        });
        if let Some((t, target, cable, sdeg)) = plan {
            self.target_v = target;
            self.force = t;
            self.cable = cable;
            self.set_servo(sdeg);
        }
        let _ = w!(out; line, self.board.newline());
        Ok(())
    }

    #[cfg(feature = "contact")]
    /// `contact <P0> <P> [<V1> <V2> <V3>]`: model only ([`crate::inverse_cmds::contact`]);
    /// the voltages are checked against the ceilings as `solve` does. Writes its reply line.
    #[inline(never)]
    fn cmd_contact<W: Write>(&self, args: &[&[u8]], out: &mut W) -> Result<(), CmdError> {
        if args.len() != 2 && args.len() != 2 + CHANNELS {
            return Err(err!("usage"; "contact <P0> <P> [<V1> <V2> <V3>]"));
        }
        let p0 = tension(number(args[0], "P0")?)?;
        let p = tension(number(args[1], "P")?)?;
        let mut v = [0.0f32; CHANNELS];
        if args.len() > 2 {
            v = [number(args[2], "V1")?, number(args[3], "V2")?, number(args[4], "V3")?];
        }
        self.check_volts(&v)?;
        let mut line: String<240> = String::new();
        let volts: &[f32] = if args.len() > 2 { &v } else { &[] };
        let _ = crate::inverse_cmds::contact(&mut line, &self.finger, p0, p, volts);
        let _ = w!(out; line, self.board.newline());
        Ok(())
    }

    fn require_disarmed(&self, what: &str) -> Result<(), CmdError> {
        if self.armed {
            return Err(err!("armed"; what, " only while disarmed"));
        }
        if self.volts.iter().any(|&v| v != 0.0) || self.enable {
            return Err(err!("armed"; what, ": HV still ramping down, wait"));
        }
        Ok(())
    }

    #[inline(never)]
    fn cmd_param<W: Write>(&mut self, args: &[&[u8]], r: &mut Reply, out: &mut W) -> Result<(), CmdError> {
        self.require_disarmed("param")?;
        let name = match args.first() {
            None => {
                let nl = self.board.newline();
                let p = self.finger.params();
                for i in PARAMS {
                    let v = p.get(i.name).unwrap_or(f64::NAN) as f32;
                    let _ = w!(out; i.name, "=", Short(v), " (", i.range, ")", nl);
                }
                for i in FW_PARAMS {
                    let _ = w!(out; i.name, "=", Short(self.fw.get(i.name).unwrap_or(0.0)), " (", i.range, ")", nl);
                }
                let _ = w!(r; "params=", PARAMS.len() + FW_PARAMS.len());
                return Ok(());
            }
            Some(n) => *n,
        };
        if args.len() > 2 {
            return Err(err!("usage"; "param [<name> [<value>]]"));
        }
        // the parameter's own name (a &'static str), found by its bytes
        let name = PARAMS.iter().map(|i| i.name).chain(FW_PARAMS.iter().map(|i| i.name)).find(|n| n.as_bytes() == name);
        let Some(name) = name else {
            return Err(err!("usage"; "no parameter ", (console::printable(args[0])), "; param lists them"));
        };
        if let Some(v) = args.get(1) {
            let v = number(v, name)?;
            if PARAMS.iter().any(|i| i.name == name) {
                if name == "n" && v != CHANNELS as f32 {
                    return Err(err!("usage"; "parameter n: the board drives ", CHANNELS, " joints"));
                }
                let mut p = *self.finger.params();
                p.set(name, v.into()).map_err(model_err)?;
                let f = Finger::new(p).map_err(model_err)?;
                let (cable, deg) = self.plan_servo(&f, &self.fw, self.force, &self.target_v)?;
                self.set_finger(f);
                self.cable = cable;
                self.set_servo(deg);
            } else {
                let mut fw = self.fw;
                fw.set(name, v)?;
                let (cable, deg) = self.plan_servo(&self.finger, &fw, self.force, &self.target_v)?;
                self.fw = fw;
                self.cable = cable;
                self.set_servo(deg);
            }
            self.recompute();
        }
        let v = match self.finger.params().get(name) {
            Some(v) => v as f32,
            None => self.fw.get(name).unwrap_or(0.0),
        };
        let _ = w!(r; name, "=", Short(v));
        Ok(())
    }

    #[inline(never)]
    fn cmd_preset(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        let [which] = args else { return Err(err!("usage"; "preset <default|paper>")) };
        let (p, name) = match *which {
            b"default" => (preset(Params::<f32>::default()), "default"),
            b"paper" => (preset(Params::<f32>::paper()), "paper"),
            w => return Err(err!("usage"; "preset ", (console::printable(w)), " is not default or paper")),
        };
        self.require_disarmed("preset")?;
        let f = Finger::new(p).map_err(model_err)?;
        let (cable, deg) = self.plan_servo(&f, &self.fw, self.force, &self.target_v)?;
        self.set_finger(f);
        self.cable = cable;
        self.set_servo(deg);
        self.recompute();
        let _ = w!(r; "preset=", name);
        Ok(())
    }
}

/// A preset as this build can hold it: without the `de` feature the finger has no stacks.
fn preset(p: Params<f32>) -> Params<f32> {
    if cfg!(feature = "de") {
        p
    } else {
        p.without_stacks()
    }
}

const HELP: &[&str] = &[
    "help - this list",
    "version - firmware name and version",
    "status - outputs, setpoints, model state, fault",
    "limits - ceilings in force",
    "solve <P> <V1> <V2> <V3> - model only, nothing moves",
    "arm | disarm - allow HV / ramp HV to 0, then drop the enable",
    "stop - emergency stop: HV off at once, cable released, disarmed",
    "volt <1|2|3|all> <V> - HV channel setpoint, slewed; needs arm",
    "force <P> - cable tension (servo); needs arm",
    #[cfg(feature = "pose")]
    "pose <d1> <d2> <d3> [<P>] - inverse: tension and voltages for these joint angles (deg); moves only when armed",
    #[cfg(feature = "contact")]
    "contact <P0> <P> [<V1> <V2> <V3>] - model only: tip force on a stop at the free tip of P0",
    "param [<name> [<value>]] - list, read or set a parameter; only while disarmed",
    "preset <default|paper> - model parameters back to a preset; only while disarmed",
    "wait <s> - run the control loop for s seconds, then reply",
];

fn no_args(args: &[&[u8]], cmd: &str) -> Result<(), CmdError> {
    if args.is_empty() {
        Ok(())
    } else {
        Err(err!("usage"; cmd, " takes no arguments"))
    }
}

fn number(tok: &[u8], what: &str) -> Result<f32, CmdError> {
    console::parse_number(tok).map_err(|e| match e {
        NumError::Syntax => err!("bad-number"; what, ": ", (console::printable(tok)), " is not a decimal number"),
        NumError::Overflow => err!("bad-number"; what, ": ", (console::printable(tok)), " is out of range"),
    })
}

/// A cable tension: >= 0 (usage), representable (limit: far past any fmax).
fn tension(p: f32) -> Result<f32, CmdError> {
    if p < 0.0 {
        return Err(err!("usage"; "tension must be >= 0 (a cable cannot push)"));
    }
    if p > 1e6 {
        return Err(err!("limit"; "tension ", Exp(p, 3), " N is past fmax"));
    }
    Ok(p)
}

fn list(r: &mut Reply, v: &[f32], prec: usize) {
    let _ = w!(r; List(v, prec));
}

/// A tip pose as `x,y,deg` (mm, mm, degrees).
struct Tip<'a>(&'a finger_model::Pose<f32>);

impl Emit for Tip<'_> {
    fn emit(&self, f: &mut dyn Write) {
        let t = self.0;
        let _ = w!(f; Fixed(t.x, 3), ",", Fixed(t.y, 3), ",", Fixed(t.theta * DEG, 2));
    }
}

fn joints(r: &mut Reply, s: &Solution<f32>) {
    let mut d = [0.0f32; CHANNELS];
    for ch in 0..CHANNELS {
        d[ch] = s.joint_angle[ch] * DEG;
    }
    list(r, &d, 3);
}
