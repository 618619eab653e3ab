//! `pose` and `contact` (docs/console.md; `contact` an addition, docs/inverse.md): the
//! arguments parsed once (`pose_args`) for both builds, the inverse's answer written as the
//! one reply line ([`pose`], [`contact`]: generic over the model's number type, the host tests
//! call them), and the handlers on [`Commands`]: the f32 inverse, or on the Cortex-M3 image the
//! fixed-point one.
//!
//! - `pose <d1> <d2> <d3> [<P>]` (degrees, N): the tension and voltages that hold the joint
//!   angles. Reply `ok force=<N> volts=<v1,v2,v3> joints=<d1,d2,d3> range=<lo,hi> settle=<s>
//!   moved=<0|1>`; a posture past the model's domain (tip behind the base, past fmax) is
//!   `err unreachable`. Armed, the
//!   answer passes the checks of `volt` and `force` before anything moves; disarmed nothing
//!   moves. A negative angle is `err unreachable` (the cable only flexes a joint).
//! - `contact <P0> <P> [<V1> <V2> <V3>]` (N, V): model only. The tip stops at the free tip of
//!   P0 at 0 V; the force it presses with at P and the voltages. Reply `ok fx=<N> fy=<N>
//!   force=<N> point=<x,y>`. P below P0 pulls the tip off the stop: `err usage`.
//!
//! What it is not: the dispatch, the armed state, the ceilings (`super::commands`).

#[cfg(any(feature = "pose", feature = "contact"))]
use core::fmt::{self, Write};
#[cfg(m3)]
use finger_model::fixed::q::{Nt, Rad};
#[cfg(m3)]
use finger_model::fixed::{FixedFinger, FixedInverseDirect};
#[cfg(feature = "contact")]
use finger_model::inverse::contact_force;
#[cfg(feature = "pose")]
use finger_model::inverse::{solve_pose_tabled_into, solve_pose_with, BranchTable, Options, PoseSolution};
#[cfg(m3)]
use finger_model::Error as ModelError;
#[cfg(any(feature = "pose", feature = "contact"))]
use finger_model::{Error, Finger, Real, MAX_JOINTS};
#[cfg(any(feature = "pose", feature = "contact"))]
use finger_protocol::const_concat;
use finger_protocol::field;
#[cfg(any(feature = "pose", feature = "contact"))]
use heapless::String;

use super::commands::Commands;
#[cfg(any(m3, feature = "contact"))]
use super::errors::model_err;
#[cfg(any(feature = "pose", feature = "contact"))]
use super::errors::{head, ErrorCode};
use super::errors::{number, tension, CmdError};
#[cfg(m3)]
use super::help::{joints, list, Reply, DEG};
use super::params::CHANNELS;
#[cfg(m3)]
use super::solves::forward;
#[cfg(any(feature = "pose", feature = "contact"))]
use crate::num::write_model_error;
use crate::num::Fixed;

/// `pose`'s arguments: the joint angles (degrees, each |d| <= 360) as `angle` takes them, and
/// the optional tension.
#[inline(always)]
fn pose_args<T: Copy>(args: &[&[u8]], zero: T, angle: impl Fn(f32) -> T) -> Result<([T; CHANNELS], Option<f32>), CmdError> {
    if args.len() != 3 && args.len() != 4 {
        return Err(err!(Usage; "pose <d1> <d2> <d3> [<P>]"));
    }
    let mut angles = [zero; CHANNELS];
    for ch in 0..CHANNELS {
        let d = number(args[ch], "angle")?;
        if !(d.abs() <= 360.0) {
            return Err(err!(Usage; "pose: joint angles are degrees, |d| <= 360"));
        }
        angles[ch] = angle(d);
    }
    let p = match args.get(3) {
        Some(t) => Some(tension(number(t, "P")?)?),
        None => None,
    };
    Ok((angles, p))
}

#[cfg(any(feature = "pose", feature = "contact"))]
/// `x` as f32 for printing (for R = f32 the round trip through f64 folds away: no f64
/// arithmetic is linked).
fn f32_of<R: Real>(x: R) -> f32 {
    x.to_f64() as f32
}

/// Write `err <code>: <message>` for a model error.
#[cfg(any(feature = "pose", feature = "contact"))]
fn write_err(out: &mut dyn Write, e: &Error) -> fmt::Result {
    head(out, e.code());
    write_model_error(out, e)
}

/// Write a comma-separated list with `prec` decimals.
#[cfg(feature = "pose")]
fn write_list<W: Write>(out: &mut W, v: impl Iterator<Item = f32>, prec: usize) -> fmt::Result {
    for (i, x) in v.enumerate() {
        if i > 0 {
            out.write_char(',')?;
        }
        Fixed(x, prec).write(out)?;
    }
    Ok(())
}

#[cfg(feature = "pose")]
/// `pose <d1> .. <dn> [<P>]`. `table`: the finger's branch table (built from `finger` with the
/// default options; None solves without it). `degrees`: the joint angles as parsed (one per joint);
/// `tension`: the optional fourth argument. `apply(tension, volts)` moves the outputs (or,
/// disarmed, nothing) or refuses with a console error. Arguments are the console's f32
/// numbers (`R::from_f64(f64::from(x))` folds to x for R = f32: no f64 conversion is linked).
/// Returns whether the command succeeded (and `apply` was called and accepted).
pub fn pose<R: Real, W: Write, F: FnOnce(R, &[R]) -> Result<(), CmdError>>(
    out: &mut W,
    finger: &Finger<R>,
    table: Option<&BranchTable<R>>,
    degrees: &[f32],
    tension: Option<f32>,
    apply: F,
) -> Result<bool, fmt::Error> {
    pose_with(out, finger, table, &Options::default(), degrees, tension, apply)
}

#[cfg(feature = "pose")]
/// [`pose`] with the inverse's options (the board's: the ceiling in force, HV full scale too);
/// `table` must have been built with the same options.
#[inline(never)]
pub fn pose_with<R, W, F>(
    out: &mut W,
    finger: &Finger<R>,
    table: Option<&BranchTable<R>>,
    opts: &Options<R>,
    degrees: &[f32],
    tension: Option<f32>,
    apply: F,
) -> Result<bool, fmt::Error>
where
    R: Real,
    W: Write,
    F: FnOnce(R, &[R]) -> Result<(), CmdError>,
{
    let n = finger.params().n;
    if degrees.len() != n {
        head(out, ErrorCode::Usage);
        w!(out; "pose <d1> .. <d", n, "> [<P>] (degrees, N)")?;
        return Ok(false);
    }
    let mut angles = [R::zero(); MAX_JOINTS];
    for (a, &d) in angles.iter_mut().zip(degrees) {
        if !d.is_finite() {
            head(out, ErrorCode::BadNumber);
            w!(out; "angle is not a finite number")?;
            return Ok(false);
        }
        *a = R::from_f64(f64::from(d)) * R::from_f64(core::f64::consts::PI / 180.0);
    }
    // the cable runs on the flexor side: it flexes a joint, it can never extend one
    if let Some(k) = degrees.iter().position(|&d| d < 0.0) {
        head(out, ErrorCode::Unreachable);
        w!(out; "joint ", k + 1, ": ", Fixed(degrees[k], 3), " deg is an extension; the cable only flexes the joints (angles >= 0)")?;
        return Ok(false);
    }
    let tension = tension.map(|t| R::from_f64(f64::from(t)));
    // (the tabled inverse writes its answer in place: no copy of the solution)
    let mut sol = PoseSolution::empty();
    let solved = match table {
        Some(t) => solve_pose_tabled_into(t, &angles[..n], tension, &mut sol),
        None => solve_pose_with(finger, &angles[..n], tension, opts).map(|s| sol = s),
    };
    if let Err(e) = solved {
        write_err(out, &e)?;
        return Ok(false);
    }
    if let Err(e) = apply(sol.tension, &sol.volts[..n]) {
        e.emit(out);
        return Ok(false);
    }
    w!(out; const_concat!("ok ", field::FORCE.first()), Fixed(f32_of(sol.tension), 4), field::VOLTS.after())?;
    write_list(out, sol.volts[..n].iter().map(|&v| f32_of(v)), 1)?;
    out.write_str(field::JOINTS.after())?;
    write_list(out, sol.angles[..n].iter().map(|&a| f32_of(a * R::from_f64(180.0 / core::f64::consts::PI))), 3)?;
    out.write_str(field::RANGE.after())?;
    write_list(out, sol.interval.iter().map(|&p| f32_of(p)), 4)?;
    Ok(true)
}

#[cfg(feature = "contact")]
/// `contact <P0> <P> [<V1> .. <Vn>]`: model only. `volts` empty (0 V) or one per joint.
pub fn contact<R, W>(out: &mut W, finger: &Finger<R>, p0: f32, p: f32, volts: &[f32]) -> Result<bool, fmt::Error>
where
    R: Real,
    W: Write,
{
    let n = finger.params().n;
    if !(volts.is_empty() || volts.len() == n) {
        head(out, ErrorCode::Usage);
        w!(out; "contact <P0> <P> [<V1> .. <V", n, ">] (N, V)")?;
        return Ok(false);
    }
    if !(p0.is_finite() && p.is_finite() && volts.iter().all(|v| v.is_finite())) {
        head(out, ErrorCode::BadNumber);
        w!(out; "not a finite number")?;
        return Ok(false);
    }
    // the stop holds the free tip of P0; a lower tension pulls the tip away from it (a
    // pull-off: the stop cannot pull), so there is no contact force to report
    if p < p0 {
        head(out, ErrorCode::Usage);
        w!(out; "contact: P ", Fixed(p, 3), " N is below P0 ", Fixed(p0, 3), " N: the tip pulls away from the stop (pull-off); a contact force needs P >= P0")?;
        return Ok(false);
    }
    let zero = [R::zero(); MAX_JOINTS];
    let mut v = [R::zero(); MAX_JOINTS];
    for (x, &y) in v.iter_mut().zip(volts) {
        *x = R::from_f64(f64::from(y));
    }
    match contact_force(finger, R::from_f64(f64::from(p0)), &zero[..n], R::from_f64(f64::from(p)), &v[..n]) {
        Ok(c) => {
            // `force_on_tip`: the stop's force on the tip (the model's, Python's); `fx`, `fy`
            // (the contract's first fields): the tip's on the stop, its opposite
            let (fx, fy) = (f32_of(c.force[0]), f32_of(c.force[1]));
            w!(out; const_concat!("ok ", field::FX.first()), Fixed(-fx, 4), field::FY.after(), Fixed(-fy, 4), field::FORCE.after(), Fixed(f32_of(c.magnitude()), 4), field::POINT.after(), Fixed(f32_of(c.point[0]), 3), ",", Fixed(f32_of(c.point[1]), 3))?;
            w!(out; field::FORCE_ON_TIP.after(), Fixed(fx, 4), ",", Fixed(fy, 4))?;
            Ok(true)
        }
        Err(e) => {
            write_err(out, &e)?;
            Ok(false)
        }
    }
}

impl Commands {
    #[cfg(feature = "pose")]
    /// `pose d1 d2 d3 [P]`: the inverse model ([`pose_with`]).
    /// Writes its reply line itself. Armed, the solution goes through the checks of `volt`
    /// and `force` ([`Commands::plan_setpoints`]) and then moves the outputs; disarmed it answers
    /// and moves nothing; refused or unreachable, nothing moves.
    #[inline(never)]
    pub(super) fn cmd_pose<W: Write>(&mut self, args: &[&[u8]], out: &mut W) -> Result<(), CmdError> {
        let (deg, p) = pose_args(args, 0.0f32, |d| d)?;
        let table = self.planner.branch_table();
        let armed = self.armed;
        let mut plan = None;
        let mut answer = None;
        let mut line: String<240> = String::new();
        let this = &*self;
        let done = pose_with(&mut line, this.planner.finger(), table, &this.planner.inverse_options(), &deg, p, |t, v| {
            let target = [v[0], v[1], v[2]];
            this.check_domain(t, &target)?;
            answer = Some(target);
            if !armed {
                return Ok(());
            }
            this.require_armed("pose")?;
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
        // the answer holds the posture once the film has relaxed; how long that takes
        if let (Ok(true), Some(v)) = (done, answer) {
            let _ = w!(&mut line; field::SETTLE.after());
            self.write_settle(&mut line, &v);
            let _ = w!(&mut line; field::MOVED.after(), armed as u8);
        }
        let _ = w!(out; line, self.nl);
        Ok(())
    }

    /// The model's domain (docs/console.md `pose`): a posture whose tension is past fmax at its
    /// voltages (a hinge's notch closed, links touching) or whose tip lies behind the base
    /// (x <= 0) is refused as `unreachable`, with the reason.
    #[cfg(feature = "pose")]
    #[inline(never)]
    pub(super) fn check_domain(&self, p: f32, v: &[f32; CHANNELS]) -> Result<(), CmdError> {
        let end = self.planner.fmax(v).map_err(super::errors::model_err)?;
        if !(p <= end.tension) {
            let why = match end.kind {
                finger_model::BranchEnd::Contact => "its notch closes (links touch)",
                _ => "its equilibrium branch ends",
            };
            return Err(err!(Unreachable; "pose: needs ", Fixed(p, 3), " N, past fmax ", Fixed(end.tension, 3), " N: at joint ", end.joint, " ", why));
        }
        let x = self.planner.forward_with(p, v, |s| s.tip().x).map_err(super::errors::model_err)?;
        if !(x > 0.0) {
            return Err(err!(Unreachable; "pose: the tip would be behind the base (x=", Fixed(x, 3), " mm), outside the model's domain"));
        }
        Ok(())
    }

    /// `settle=`'s value: the longest channel's settling time from rest to within 1 % of its
    /// target thickness, s, in the board's mode (`param shaped`), at the slew in force
    /// (app/film.rs); `-` past the longest time looked for or for a voltage without an
    /// equilibrium.
    #[cfg(not(m3))]
    #[inline(never)]
    pub(super) fn write_settle(&self, out: &mut dyn Write, volts: &[f32; CHANNELS]) {
        let mut worst = Some(0.0f32);
        for ch in 0..CHANNELS {
            // channels at the same voltage settle together
            if volts[..ch].contains(&volts[ch]) {
                continue;
            }
            let t = match self.film.settle(volts[ch], self.fw.slew, self.fw.shaped) {
                Ok(Some(t)) => Some(t),
                _ => None,
            };
            worst = match (worst, t) {
                (Some(a), Some(b)) => Some(a.max(b)),
                _ => None,
            };
        }
        match worst {
            Some(t) => {
                let _ = w!(out; Fixed(t, 2));
            }
            None => {
                let _ = w!(out; "-");
            }
        }
    }

    #[cfg(feature = "contact")]
    /// `contact <P0> <P> [<V1> <V2> <V3>]`: model only ([`contact`]);
    /// the voltages are checked against the ceilings as `solve` does. Writes its reply line.
    #[inline(never)]
    pub(super) fn cmd_contact<W: Write>(&self, args: &[&[u8]], out: &mut W) -> Result<(), CmdError> {
        if args.len() != 2 && args.len() != 2 + CHANNELS {
            return Err(err!(Usage; "contact <P0> <P> [<V1> <V2> <V3>]"));
        }
        let p0 = tension(number(args[0], "P0")?)?;
        let p = tension(number(args[1], "P")?)?;
        let mut v = [0.0f32; CHANNELS];
        if args.len() > 2 {
            v = [number(args[2], "V1")?, number(args[3], "V2")?, number(args[4], "V3")?];
        }
        self.check_volts(&v)?;
        // past fmax: `limits`' figure, the one every refusal quotes (the model's own check
        // below finds the same limit to its bisection's last digit)
        if let Ok(b) = self.planner.fmax(&v) {
            if p > b.tension {
                return Err(model_err(finger_model::Error::ForceLimit { tension: p.into(), fmax: b.tension.into() }));
            }
        }
        let mut line: String<240> = String::new();
        let volts: &[f32] = if args.len() > 2 { &v } else { &[] };
        let _ = contact(&mut line, self.planner.finger(), p0, p, volts);
        let _ = w!(out; line, self.nl);
        Ok(())
    }
}

#[cfg(all(m3, feature = "pose"))]
compile_error!("the Cortex-M3 image's pose is the fixed-point one (app/pose.rs): build it without feature pose");

#[cfg(m3)]
impl Commands {
    /// `pose <d1> <d2> <d3> [<P>]` on the fixed-point inverse (`FixedInverseDirect`, the
    /// ceiling in force, the top voltage the F405's: `Options::top` of it): at the given
    /// tension, or without `<P>` at the F405's tension rule (the midpoint of the tensions that
    /// hold the posture, `solve_free`). The voltages, then, armed, the checks of `volt` and
    /// `force` ([`Commands::plan_setpoints`]) and the outputs move; disarmed nothing moves.
    /// Reply `ok force= volts= joints=` (joints: the fixed-point forward solve at that answer),
    /// and without `<P>` `range=` (the interval, as the F405's).
    #[inline(never)]
    pub(super) fn cmd_pose(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        let (rad, given) = pose_args(args, Rad::ZERO, |d| Rad::from_f32(d / DEG))?;
        let mut ff = FixedFinger::empty();
        ff.prepare(self.planner.finger(), &[0.0; CHANNELS]).map_err(model_err)?;
        let top = finger_model::inverse::Options::<f32>::default().top;
        let inv = FixedInverseDirect::new(self.planner.finger(), &ff, self.vmax[0] * top).map_err(model_err)?;
        let mut at = Nt::from_f32(given.unwrap_or(0.0));
        let res = match given {
            Some(_) => inv.solve(&rad, at).map(|s| (s, None)),
            None => inv.solve_free(&rad, &mut at).map(|(s, i)| (s, Some(i))),
        };
        let (sol, range) = res.map_err(|e| match e {
            // the fixed-point inverse's range is in joint angles (the f32 one's in compliance)
            ModelError::Unreachable { joint, needed, min, max } => {
                let d = |x: f64| Fixed(x as f32 * DEG, 3);
                err!(Unreachable; "joint ", joint, ": needs ", d(needed), " deg, its stack spans ", d(min), "..", d(max), " deg at ", Fixed(at.to_f32(), 3), " N")
            }
            e => model_err(e),
        })?;
        let p = sol.tension.to_f32();
        let v = inv.volts(&sol).map_err(model_err)?;
        let target = [v[0], v[1], v[2]];
        // the ceilings as `volt` checks them, armed or not; 0 V (rest thickness) is off
        self.check_volts_of(&target, true)?;
        let held = forward(self.planner.finger(), p, &target).map_err(model_err)?;
        if self.armed {
            self.require_armed("pose")?;
            let (cable, sdeg) = self.plan_setpoints(p, &target)?;
            self.target_v = target;
            self.force = p;
            self.cable = cable;
            self.set_servo(sdeg);
        }
        let _ = w!(r; field::FORCE.first(), Fixed(p, 4), field::VOLTS.after());
        list(r, &target, 1);
        let _ = w!(r; field::JOINTS.after());
        joints(r, &held);
        if let Some(i) = range {
            let _ = w!(r; field::RANGE.after(), Fixed(i[0].to_f32(), 4), ",", Fixed(i[1].to_f32(), 4));
        }
        Ok(())
    }
}
