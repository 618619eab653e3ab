//! The documented domain's cases (docs/model.md), one function per property, shared by the
//! property tests (model/tests/proptest_domain.rs, CI) and the soak
//! (`cargo run --example soak`). Each returns the outcome's name (an answer, or a
//! typed refusal) or, as `Err`, a violation: a NaN or infinity in an answer, `NotConverged`,
//! a fault, or an answer that does not hold.
//!
//! The domain: the hardware's parameter sets (the default and the paper preset) with every
//! hinge model (m = 1..8, plate modulus on/off, flexible links on/off), voltages from 0 to the
//! ceiling (1 - 1e-4 of it), tensions from 0 to fmax at those voltages; contact on the default
//! finger with P0 0.05-5 N.

use finger_model::inverse::{contact_force, solve_pose};
use finger_model::{Error, Finger, Method, Params};

/// A finger of the domain.
pub fn finger(paper: bool, m: usize, plate: bool, flex_links: bool) -> Finger<f64> {
    let base = if paper { Params::paper() } else { Params::default() };
    Finger::new(Params { m, plate, flex_links, ..base }).expect("a preset with any hinge model is valid")
}

fn volts(f: &Finger<f64>, vfrac: [f64; 3]) -> Vec<f64> {
    let top = f.voltage_ceiling() * (1.0 - 1e-4);
    (0..f.params().n).map(|k| vfrac[k % 3] * top).collect()
}

fn refusal(e: &Error) -> Option<&'static str> {
    match e {
        Error::ForceLimit { .. } => Some("refused: past fmax"),
        Error::Contact { .. } => Some("refused: links touching"),
        Error::LimitPoint { .. } => Some("refused: stop out of reach"),
        Error::PullingStop { .. } => Some("refused: the stop pulls"),
        _ => None,
    }
}

fn fmax_of(f: &Finger<f64>, v: &[f64]) -> Result<f64, String> {
    match f.fmax(v) {
        Ok(b) if b.tension.is_finite() && b.tension > 0.0 => Ok(b.tension),
        Ok(b) => Err(format!("fmax {b:?}")),
        Err(e) => Err(format!("fmax V={v:?}: {e:?}")),
    }
}

/// fmax at the voltages: an answer, finite and positive, never `NotConverged`.
pub fn fmax(f: &Finger<f64>, vfrac: [f64; 3]) -> Result<&'static str, String> {
    fmax_of(f, &volts(f, vfrac)).map(|_| "answer")
}

/// The forward solve at `frac` x fmax: a finite answer (or a branch end, typed).
pub fn forward(f: &Finger<f64>, frac: f64, vfrac: [f64; 3]) -> Result<&'static str, String> {
    let v = volts(f, vfrac);
    let p = frac * fmax_of(f, &v)?;
    match f.solve(p, &v, Method::converged()) {
        Ok(s) => {
            let n = s.n;
            let finite = s.nodes[..=n].iter().all(|q| q.x.is_finite() && q.y.is_finite() && q.theta.is_finite())
                && s.residual.is_finite()
                && s.cable_excursion.is_finite();
            if finite {
                Ok("answer")
            } else {
                Err(format!("forward P={p} V={v:?}: non-finite {s:?}"))
            }
        }
        Err(e) => refusal(&e).ok_or_else(|| format!("forward P={p} V={v:?}: {e:?}")),
    }
}

/// The inverse round trip of a posture the forward model reaches (tension `frac` x
/// min(fmax, 8 N)): found, and the forward solve of its answer holds it to 1e-8 rad.
pub fn inverse(f: &Finger<f64>, frac: f64, vfrac: [f64; 3]) -> Result<&'static str, String> {
    let v = volts(f, vfrac);
    let p = frac * fmax_of(f, &v)?.min(8.0);
    let n = f.params().n;
    let s = f.solve(p, &v, Method::converged()).map_err(|e| format!("forward P={p}: {e:?}"))?;
    let inv = solve_pose(f, &s.joint_angle[..n], None).map_err(|e| format!("inverse of P={p} V={v:?}: {e:?}"))?;
    let back = f.solve(inv.tension, &inv.volts[..n], Method::converged()).map_err(|e| format!("forward of the inverse: {e:?}"))?;
    for k in 0..n {
        let err = (back.joint_angle[k] - s.joint_angle[k]).abs();
        if !(err <= 1e-8) {
            return Err(format!("inverse of P={p} V={v:?}: joint {k} off by {err:e} rad"));
        }
    }
    Ok("answer")
}

/// Contact on `f`: stop at the free tip of (P0, 0 V), tension `pfrac` x fmax at the voltages;
/// an answer is a forward equilibrium under its tip load with the tip on the stop.
pub fn contact(f: &Finger<f64>, p0: f64, pfrac: f64, vfrac: [f64; 3]) -> Result<&'static str, String> {
    let v = volts(f, vfrac);
    let p = pfrac * fmax_of(f, &v)?;
    let n = f.params().n;
    let len = f.params().l * n as f64;
    match contact_force(f, p0, &vec![0.0; n], p, &v) {
        Ok(c) => {
            let fwd = f.equilibrium_residual(&c.solution).map_err(|e| format!("contact P0={p0} P={p}: {e:?}"))?;
            let on = (c.solution.tip().x - c.point[0]).hypot(c.solution.tip().y - c.point[1]);
            if c.force.iter().all(|x| x.is_finite()) && fwd < 1e-8 && on < 1e-8 * len {
                Ok("answer")
            } else {
                Err(format!("contact P0={p0} P={p} V={v:?}: force {:?}, relative wrench imbalance {fwd:e}, tip {on:e} mm off", c.force))
            }
        }
        Err(e) => refusal(&e).ok_or_else(|| format!("contact P0={p0} P={p} V={v:?}: {e:?}")),
    }
}
