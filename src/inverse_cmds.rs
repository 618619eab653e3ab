//! Console commands of the inverse model (issue 4): `pose` (CONSOLE.md) and `contact` (an
//! addition, docs/inverse.md). Each handler takes the already parsed arguments, runs the model
//! and writes the one final reply line (without the line ending); the dispatcher
//! ([`crate::App`]) owns parsing, the armed state and the outputs.
//!
//! - `pose <d1> <d2> <d3> [<P>]` (degrees, N): the tension and voltages that hold the joint
//!   angles. Reply `ok force=<N> volts=<v1,v2,v3> joints=<d1,d2,d3> range=<lo,hi>` (`range`,
//!   the tensions that can hold the posture, is an addition). The outputs move only through
//!   the `apply` callback: the dispatcher checks there what `volt` and `force` check (fault,
//!   ceilings, fmax, servo travel) and moves nothing while disarmed; if `apply` refuses, its
//!   error is the reply and nothing has moved. Unreachable:
//!   `err unreachable: joint k: needs compliance ..., the ceiling allows ...`, `apply` is not
//!   called; a negative angle is `err unreachable` as such (the cable only flexes a joint).
//! - `contact <P0> <P> [<V1> <V2> <V3>]` (N, V): model only, nothing moves. The tip stops at
//!   the free tip of P0 at 0 V; at P with the voltages (default 0 V) the force the tip presses
//!   with. Reply `ok fx=<N> fy=<N> force=<N> point=<x,y>`: (fx, fy) the force of the finger
//!   on the object (base frame), force its magnitude, point the contact point (mm). P below
//!   P0 would pull the tip off the stop: `err usage: ... (pull-off)`.
//!
//! no_std, no allocation, no core formatting (crate::num, crate::out): replies go to any
//! `core::fmt::Write`.

use core::fmt::{self, Write};
#[cfg(feature = "contact")]
use finger_model::inverse::contact_force;
#[cfg(feature = "pose")]
use finger_model::inverse::{solve_pose_tabled_into, solve_pose_with, BranchTable, Options, PoseSolution};
use finger_model::{Error, Finger, Real, MAX_JOINTS};

#[cfg(feature = "pose")]
use crate::app::CmdError;
use crate::num::{write_model_error, Fixed};

/// `x` as f32 for printing (for R = f32 the round trip through f64 folds away: no f64
/// arithmetic is linked).
fn f32_of<R: Real>(x: R) -> f32 {
    x.to_f64() as f32
}

/// Write `err <code>: <message>` for a model error.
fn write_err(out: &mut dyn Write, e: &Error) -> fmt::Result {
    w!(out; "err ", e.code(), ": ")?;
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
pub fn pose<R, W, F>(
    out: &mut W,
    finger: &Finger<R>,
    table: Option<&BranchTable<R>>,
    degrees: &[f32],
    tension: Option<f32>,
    apply: F,
) -> Result<bool, fmt::Error>
where
    R: Real,
    W: Write,
    F: FnOnce(R, &[R]) -> Result<(), CmdError>,
{
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
        w!(out; "err usage: pose <d1> .. <d", n, "> [<P>] (degrees, N)")?;
        return Ok(false);
    }
    let mut angles = [R::zero(); MAX_JOINTS];
    for (a, &d) in angles.iter_mut().zip(degrees) {
        if !d.is_finite() {
            w!(out; "err bad-number: angle is not a finite number")?;
            return Ok(false);
        }
        *a = R::from_f64(f64::from(d)) * R::from_f64(core::f64::consts::PI / 180.0);
    }
    // the cable runs on the flexor side: it flexes a joint, it can never extend one
    if let Some(k) = degrees.iter().position(|&d| d < 0.0) {
        w!(out; "err unreachable: joint ", k + 1, ": ", Fixed(degrees[k], 3), " deg is an extension; the cable only flexes the joints (angles >= 0)")?;
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
        w!(out; "err ", e.code, ": ", e.msg)?;
        return Ok(false);
    }
    w!(out; "ok force=", Fixed(f32_of(sol.tension), 4), " volts=")?;
    write_list(out, sol.volts[..n].iter().map(|&v| f32_of(v)), 1)?;
    out.write_str(" joints=")?;
    write_list(out, sol.angles[..n].iter().map(|&a| f32_of(a * R::from_f64(180.0 / core::f64::consts::PI))), 3)?;
    out.write_str(" range=")?;
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
        w!(out; "err usage: contact <P0> <P> [<V1> .. <V", n, ">] (N, V)")?;
        return Ok(false);
    }
    if !(p0.is_finite() && p.is_finite() && volts.iter().all(|v| v.is_finite())) {
        w!(out; "err bad-number: not a finite number")?;
        return Ok(false);
    }
    // the stop holds the free tip of P0; a lower tension pulls the tip away from it (a
    // pull-off: the stop cannot pull), so there is no contact force to report
    if p < p0 {
        w!(out; "err usage: contact: P ", Fixed(p, 3), " N is below P0 ", Fixed(p0, 3), " N: the tip pulls away from the stop (pull-off); a contact force needs P >= P0")?;
        return Ok(false);
    }
    let zero = [R::zero(); MAX_JOINTS];
    let mut v = [R::zero(); MAX_JOINTS];
    for (x, &y) in v.iter_mut().zip(volts) {
        *x = R::from_f64(f64::from(y));
    }
    match contact_force(finger, R::from_f64(f64::from(p0)), &zero[..n], R::from_f64(f64::from(p)), &v[..n]) {
        Ok(c) => {
            // the finger presses on the object with minus the object's force on the tip
            let (fx, fy) = (f32_of(-c.force[0]), f32_of(-c.force[1]));
            w!(out; "ok fx=", Fixed(fx, 4), " fy=", Fixed(fy, 4), " force=", Fixed(f32_of(c.magnitude()), 4), " point=", Fixed(f32_of(c.point[0]), 3), ",", Fixed(f32_of(c.point[1]), 3))?;
            Ok(true)
        }
        Err(e) => {
            write_err(out, &e)?;
            Ok(false)
        }
    }
}
