//! The handlers of the commands that move or read the outputs and the model (`status`,
//! `limits`, `solve`, `volt`, `force`, `param`, `preset`, `cal`, and `arm`'s and `disarm`'s
//! checks): each checks everything first and changes [`Commands`] only when all checks passed.
//!
//! What it is not: the dispatch and the command side's state (`super`), the planning (the
//! finger, fmax, the branch table: `super::super::planner`).

use core::fmt::Write;

use finger_model::calibration::KEEPS_CALIBRATION;
use finger_model::params::PARAMS;
use finger_model::{Calibration, Params};
use finger_protocol::{const_concat, field};

#[cfg(not(m3))]
use super::largest_below;
use super::Commands;
use crate::app::errors::{model_err, number, tension, CmdError};
use crate::app::help::{joints, list, solve_reply, Reply, Tip, DEG};
use crate::app::params::{board_params, calibration_for, preset, CAL_NAMES, CHANNELS, FW_PARAMS};
#[cfg(m3)]
use crate::app::solves::forward_stiffness;
use crate::console;
use crate::num::{Fixed, Short};

impl Commands {
    #[inline(never)]
    pub(in crate::app) fn cmd_status(&self, r: &mut Reply) {
        let _ = w!(r; field::ARMED.first(), self.armed as u8, field::FORCE.after(), Fixed(self.force, 3), field::VOLTS.after());
        list(r, &self.volts, 1);
        // each stack now: the film creeps under a held voltage (the control tick's state)
        let stack_mm = self.stack_mm();
        let mut thick = [0.0f32; CHANNELS];
        for ch in 0..CHANNELS {
            // never past the rest thickness (the solve's domain); NaN (the M3's) stays NaN
            let t = stack_mm * self.stack_ratio[ch];
            thick[ch] = if t > stack_mm { stack_mm } else { t };
        }
        let _ = w!(r; field::THICK.after());
        list(r, &thick, 4);
        let mut fault = self.fault;
        #[cfg(feature = "settings")]
        {
            fault = fault.or(self.config_fault());
        }
        // the posture of the stacks as they are now, not as they will relax
        let shown = self.planner.forward_now(self.force, &self.volts, &thick, |s| {
            let _ = w!(r; field::JOINTS.after());
            joints(r, s);
            let tip = s.tip();
            let _ = w!(r; field::TIP.after(), Tip(&tip));
        });
        if shown.is_err() {
            let _ = w!(r; const_concat!(field::JOINTS.after(), "-,-,-", field::TIP.after(), "-,-,-"));
            fault = fault.or(Some("model"));
        }
        let _ =
            w!(r; field::CABLE.after(), Fixed(self.cable, 3), field::SERVO.after(), Fixed(self.servo_deg, 2), field::FAULT.after(), fault.unwrap_or("none"));
        let _ = w!(r; field::ENABLE.after(), self.enable as u8, field::TARGET.after());
        list(r, &self.target_v, 1);
        // each stack once the film has relaxed at the targets
        let mut eq = [0.0f32; CHANNELS];
        for ch in 0..CHANNELS {
            eq[ch] = stack_mm * self.film.equilibrium_ratio(self.target_v[ch]).unwrap_or(0.0);
        }
        let _ = w!(r; field::THICK_EQ.after());
        list(r, &eq, 4);
        #[cfg(not(m3))]
        if let Some(sv) = self.sense {
            // the read-back (docs/console.md "Measured HV"): measured volts, µA, the sensed
            // thickness (mm; `-` until measured), each channel's ceiling now and its film check
            let _ = w!(r; field::VMEAS.after());
            list(r, &sv.volts, 1);
            let _ = w!(r; field::IMEAS.after());
            list(r, &sv.current_ua, 3);
            let _ = w!(r; field::THICK_MEAS.after());
            for ch in 0..CHANNELS {
                let s = sv.stack_ratio[ch];
                let _ = if ch > 0 { r.write_str(",") } else { Ok(()) };
                let _ = if s > 0.0 { w!(r; Fixed(stack_mm * s, 4)) } else { r.write_str("-") };
            }
            let _ = w!(r; field::VCEIL.after());
            list(r, &sv.ceiling_v, 1);
            let _ = w!(r; field::FILM_CHECK.after());
            for ch in 0..CHANNELS {
                let _ = if ch > 0 { r.write_str(",") } else { Ok(()) };
                let _ = r.write_str(if sv.disagreed[ch] { "thinner" } else { "ok" });
            }
            // the channel whose read-back latched the fault, 1-based (only while one is latched)
            if let (Some(k), Some(_)) = (self.fault_ch, self.fault) {
                let _ = w!(r; field::FAULT_CH.after(), k + 1);
            }
        }
        // the M3 image: no read-back fields, the fault's channel alone
        #[cfg(m3)]
        if let (Some(k), Some(_)) = (self.fault_ch, self.fault) {
            let _ = w!(r; field::FAULT_CH.after(), k + 1);
        }
        #[cfg(not(m3))]
        self.orientation(r);
    }

    /// ` grav=<m/s²> grav_dir=<deg>`: the orientation in force (`status`, `limits`; not on the
    /// Cortex-M3 image: its flash, and its fixed-point model has no gravity).
    #[cfg(not(m3))]
    fn orientation(&self, r: &mut Reply) {
        let p = self.planner.finger().params();
        let _ = w!(r; field::GRAV.after(), Short(p.grav), field::GRAV_DIR.after(), Short(p.grav_dir));
    }

    /// A stack's thickness at rest, mm: layers x z0 of the model (0 without stacks).
    pub(in crate::app) fn stack_mm(&self) -> f32 {
        let p = self.planner.finger().params();
        p.layers as f32 * p.z0
    }

    #[inline(never)]
    pub(in crate::app) fn cmd_limits(&self, r: &mut Reply) {
        let _ = w!(r; field::VMAX.first());
        list(r, &self.vmax, 1);
        let p = self.planner.finger().params();
        let _ = w!(r; field::VPULLIN.after(), Fixed(self.planner.finger().pull_in_voltage(), 1), field::SUPPLY.after(), Fixed(p.v_supply, 1), field::MARGIN.after(), Short(p.margin));
        match self.planner.fmax(&self.target_v) {
            Ok(b) => {
                let kind = match b.kind {
                    finger_model::BranchEnd::Contact => "contact",
                    finger_model::BranchEnd::LimitPoint => "limit-point",
                    finger_model::BranchEnd::SearchBound => "search-bound",
                };
                let _ = w!(r; field::FMAX.after(), Fixed(b.tension, 4), field::FMAX_END.after(), kind, ",", b.joint);
            }
            Err(_) => {
                let _ = w!(r; const_concat!(field::FMAX.after(), "-", field::FMAX_END.after(), "error"));
            }
        }
        let _ = w!(r; field::SLEW.after(), Short(self.fw.slew), const_concat!(field::SERVO.after(), "0,"), Short(self.fw.servo_range), field::CABLE_MAX.after(), Fixed(self.fw.servo_range / DEG * self.fw.spool_r, 2), field::DUTYMAX.after());
        let d = self.duty_max;
        let _ = w!(r; d[0], ",", d[1], ",", d[2], field::VHOLD.after(), Fixed(self.film.hold_ceiling(), 1));
        // vmax itself is refused (at or past the ceiling): the largest `volt` takes, 0.1 V steps
        #[cfg(not(m3))]
        {
            let mut ok = [0.0f32; CHANNELS];
            for ch in 0..CHANNELS {
                ok[ch] = largest_below(self.vmax[ch]);
            }
            let _ = w!(r; field::VMAX_OK.after());
            list(r, &ok, 1);
        }
        #[cfg(not(m3))]
        self.orientation(r);
    }

    /// Check channel voltages against the ceilings: `limit` at or past ([`largest_below`]).
    pub(in crate::app) fn check_volts(&self, v: &[f32; CHANNELS]) -> Result<(), CmdError> {
        self.check_volts_of(v, false)
    }

    /// As [`Commands::check_volts`]; with `zero_is_off`, a channel at 0 V passes whatever its
    /// ceiling (a computed answer, such as `pose`'s on a finger without stacks).
    #[inline(never)]
    pub(in crate::app) fn check_volts_of(&self, v: &[f32; CHANNELS], zero_is_off: bool) -> Result<(), CmdError> {
        for ch in 0..CHANNELS {
            if zero_is_off && v[ch] == 0.0 {
                continue;
            }
            // NaN-proof: every comparison is written so that NaN fails it
            if !v[ch].is_finite() {
                return Err(err!(Limit; "channel ", (ch + 1), ": voltage is not a finite number"));
            }
            if !(v[ch] >= 0.0) {
                return Err(err!(Usage; "channel ", (ch + 1), ": voltage must be >= 0"));
            }
            if !(v[ch] < self.vmax[ch]) {
                return Err(
                    err!(Limit; "channel ", (ch + 1), ": ", Fixed(v[ch], 1), " V is at or past the ceiling ", Fixed(self.vmax[ch], 1), " V (see limits)"),
                );
            }
        }
        Ok(())
    }

    #[inline(never)]
    /// The arguments of a model-only solve (`solve`, `shape`): `<P> <V1> <V2> <V3>`, the
    /// voltages optional on a finger without stacks (layers = 0), where 0 V is off, never a
    /// request. Checked as every voltage is.
    pub(in crate::app) fn model_request(&self, args: &[&[u8]], usage: &str) -> Result<(f32, [f32; CHANNELS]), CmdError> {
        let v = match args {
            [_, v1, v2, v3] => [number(v1, "V1")?, number(v2, "V2")?, number(v3, "V3")?],
            [_] if self.planner.finger().params().layers == 0 => [0.0; CHANNELS],
            _ => return Err(err!(Usage; usage, " (", usage.split(' ').next().unwrap_or(""), " <P> without stacks)")),
        };
        let p = tension(number(args[0], "P")?)?;
        self.check_volts_of(&v, true)?;
        Ok((p, v))
    }

    #[inline(never)]
    pub(in crate::app) fn cmd_solve(&self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        let (p, vf) = self.model_request(args, "solve <P> <V1> <V2> <V3>")?;
        #[cfg(not(m3))]
        return self
            .planner
            .forward_with(p, &vf, |sol| solve_reply(r, sol, self.planner.finger().tip_stiffness(sol).map_err(model_err)?))
            .map_err(|e| model_err(self.past_fmax(p, &vf, e)))?;
        // the M3's: from the fixed-point state (app/m3.rs)
        #[cfg(m3)]
        {
            let (sol, k) = forward_stiffness(self.planner.finger(), p, &vf).map_err(model_err)?;
            solve_reply(r, &sol, k)
        }
    }

    /// A solve that ran off the branch's end (links touching, a limit point) quotes the limit
    /// itself, fmax at its voltages (`limits`' figure, `force`'s refusal), not the tension
    /// where the solver's steps found the end.
    #[cfg(not(m3))]
    fn past_fmax(&self, p: f32, volts: &[f32; CHANNELS], e: finger_model::Error) -> finger_model::Error {
        use finger_model::Error;
        match e {
            // the planner's fmax: `limits`' own figure (its table's, when it has one)
            // under gravity the coupled solve's continuation can also stall there (NotConverged)
            Error::Contact { .. } | Error::LimitPoint { .. } | Error::NotConverged { .. } => match self.planner.fmax(volts) {
                Ok(b) if p > b.tension => Error::ForceLimit { tension: p.into(), fmax: b.tension.into() },
                _ => e,
            },
            _ => e,
        }
    }

    /// The servo where `plan` ([`Commands::plan_servo`] of the present tension) holds it; where
    /// it cannot be held, the cable released (tension 0).
    pub(in crate::app) fn hold_or_release(&mut self, plan: Result<(f32, f32), CmdError>) {
        match plan {
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
    }

    #[inline(never)]
    pub(in crate::app) fn cmd_disarm(&mut self) -> Result<(), CmdError> {
        if !self.armed {
            return Ok(());
        }
        // the cable keeps its tension, held at the posture of 0 V; if that cannot be
        // held, the cable is released
        let zero = [0.0; CHANNELS];
        self.hold_or_release(self.plan_servo(self.planner.finger(), &self.fw, self.force, &zero));
        // the control core ramps the HV to 0, then drops the enable
        self.armed = false;
        self.target_v = zero;
        Ok(())
    }

    #[inline(never)]
    pub(in crate::app) fn cmd_volt(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        let [ch, v] = args else { return Err(err!(Usage; "volt <1|2|3|all> <V>")) };
        let chans: &[usize] = match *ch {
            b"1" => &[0],
            b"2" => &[1],
            b"3" => &[2],
            b"all" => &[0, 1, 2],
            c => return Err(err!(Usage; "volt: channel ", (console::printable(c)), " is not 1, 2, 3 or all")),
        };
        let v = number(v, "V")?;
        if !(v >= 0.0) {
            return Err(err!(Usage; "volt: voltage must be >= 0"));
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
        let _ = w!(r; field::VOLTS.first());
        list(r, &self.target_v, 1);
        Ok(())
    }

    pub(in crate::app) fn require_armed(&self, what: &str) -> Result<(), CmdError> {
        if let Some(f) = self.fault {
            return Err(self.latched(f));
        }
        if !self.armed {
            return Err(err!(NotArmed; what, " needs arm"));
        }
        Ok(())
    }

    #[inline(never)]
    pub(in crate::app) fn cmd_force(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        let [p] = args else { return Err(err!(Usage; "force <P>")) };
        let p = tension(number(p, "P")?)?;
        self.require_armed("force")?;
        let (cable, deg) = self.plan_setpoints(p, &self.target_v)?;
        self.force = p;
        self.cable = cable;
        self.set_servo(deg);
        let _ = w!(r; field::FORCE.first(), Fixed(self.force, 3), field::CABLE.after(), Fixed(self.cable, 3), field::SERVO.after(), Fixed(self.servo_deg, 2));
        Ok(())
    }

    pub(in crate::app) fn require_disarmed(&self, what: &str) -> Result<(), CmdError> {
        if self.armed {
            return Err(err!(Armed; what, " only while disarmed"));
        }
        if self.volts.iter().any(|&v| v != 0.0) || self.enable {
            return Err(err!(Armed; what, ": HV still ramping down, wait"));
        }
        Ok(())
    }

    #[inline(never)]
    pub(in crate::app) fn cmd_param<W: Write>(&mut self, args: &[&[u8]], r: &mut Reply, out: &mut W) -> Result<(), CmdError> {
        self.require_disarmed("param")?;
        let name = match args.first() {
            None => {
                let nl = self.nl;
                let p = self.planner.finger().params();
                let model = PARAMS.iter().map(|i| (i.name, i.range, p.get(i.name).unwrap_or(f64::NAN) as f32));
                let fw = FW_PARAMS.iter().map(|i| (i.name, i.range, self.fw.get(i.name).unwrap_or(0.0)));
                for (name, range, v) in model.chain(fw) {
                    let _ = w!(out; name, "=", Short(v), " (", range, ")", nl);
                }
                let _ = w!(r; field::PARAMS.first(), PARAMS.len() + FW_PARAMS.len());
                return Ok(());
            }
            Some(n) => *n,
        };
        if args.len() > 2 {
            return Err(err!(Usage; "param [<name> [<value>]]"));
        }
        // the parameter's own name (a &'static str), found by its bytes
        let name = PARAMS.iter().map(|i| i.name).chain(FW_PARAMS.iter().map(|i| i.name)).find(|n| n.as_bytes() == name);
        let Some(name) = name else {
            return Err(err!(Usage; "no parameter ", (console::printable(args[0])), "; param lists them"));
        };
        #[allow(unused_mut)]
        let mut cal_changed = false;
        if let Some(v) = args.get(1) {
            let v = number(v, name)?;
            if PARAMS.iter().any(|i| i.name == name) {
                if name == "n" && v != CHANNELS as f32 {
                    return Err(err!(Usage; "parameter n: the board drives ", CHANNELS, " joints"));
                }
                let mut p = *self.planner.finger().params();
                p.set(name, v.into()).map_err(model_err)?;
                // the FE calibration belongs to the mechanical parameters it was computed for
                let was = *self.planner.finger().calibration();
                let cal = if KEEPS_CALIBRATION.contains(&name) { was } else { calibration_for(&p) };
                self.adopt_model(p, cal)?;
                // said in the reply, not in the Cortex-M3 image (its flash)
                #[cfg(not(m3))]
                {
                    cal_changed = cal != was;
                }
            } else {
                let mut fw = self.fw;
                fw.set(name, v)?;
                let (cable, deg) = self.plan_servo(self.planner.finger(), &fw, self.force, &self.target_v)?;
                self.fw = fw;
                self.cable = cable;
                self.set_servo(deg);
                self.recompute();
            }
        }
        let v = match self.planner.finger().params().get(name) {
            Some(v) => v as f32,
            None => self.fw.get(name).unwrap_or(0.0),
        };
        let _ = w!(r; name, "=", Short(v));
        if cal_changed {
            // the set left (or came back to) the finger the FE calibration belongs to
            let _ = w!(r; field::CAL.after());
            self.write_cal(r);
        }
        Ok(())
    }

    #[inline(never)]
    pub(in crate::app) fn cmd_preset(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        let [which] = args else { return Err(err!(Usage; "preset <default|paper>")) };
        let (p, name) = match *which {
            b"default" => (preset(board_params()), "default"),
            b"paper" => (preset(Params::<f32>::paper()), "paper"),
            w => return Err(err!(Usage; "preset ", (console::printable(w)), " is not default or paper")),
        };
        self.require_disarmed("preset")?;
        self.adopt_model(p, calibration_for(&p))?;
        let _ = w!(r; field::PRESET.first(), name);
        Ok(())
    }

    /// `cal [<h1> <h2> <h3> <h4> <ea0> <ea1> <ei0> <ei1> | none]`: the model's FE calibration
    /// (`finger_model::Calibration`): read it, or set / clear it while disarmed. A
    /// change rebuilds the finger, as `param` does; refused, nothing changes.
    #[inline(never)]
    pub(in crate::app) fn cmd_cal(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        #[cfg(not(m3))]
        if matches!(args.first(), Some(&(b"show" | b"vmon" | b"c0"))) {
            return self.cmd_cal_hv(args, r);
        }
        let cal = match args {
            [] => None,
            [w] if *w == b"none" => Some(Calibration::none()),
            [_, _, _, _, _, _, _, _] => {
                let mut g = [0.0f32; 8];
                for k in 0..8 {
                    g[k] = number(args[k], CAL_NAMES[k])?;
                }
                Some(Calibration { hinge: [g[0], g[1], g[2], g[3]], stack_axial: [g[4], g[5]], stack_bending: [g[6], g[7]] })
            }
            _ => return Err(err!(Usage; "cal [<h1> <h2> <h3> <h4> <ea0> <ea1> <ei0> <ei1> | none]")),
        };
        if let Some(cal) = cal {
            self.require_disarmed("cal")?;
            self.adopt_model(*self.planner.finger().params(), cal)?;
        }
        let _ = w!(r; field::CAL.first());
        self.write_cal(r);
        Ok(())
    }

    /// The eight calibration factors in force, comma-separated (`cal=`'s value).
    fn write_cal(&self, r: &mut Reply) {
        let c = self.planner.finger().calibration();
        let g = [c.hinge[0], c.hinge[1], c.hinge[2], c.hinge[3], c.stack_axial[0], c.stack_axial[1], c.stack_bending[0], c.stack_bending[1]];
        list(r, &g, 6);
    }
}
