//! The inverse under gravity (docs/inverse.md "Gravity"). The target angles fix the posture up
//! to the joints' small deflections, so the distal weight at that posture is a fixed load on
//! each joint and link (`Finger::weight_at_posture`); with those loads held the joints decouple
//! again and the inverse without gravity (`general`, `fast`) solves them. Its answer's posture
//! moves the loads a little: repeated until they stop moving. What it is not: a second march
//! (every joint solve is the one march, with the held load as its external load).

use super::{fast, general, takes_general, Options, PoseSolution};
use crate::error::Error;
use crate::finger::Finger;
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;

/// Most rounds of loads and solve.
const ROUNDS: u32 = 30;

/// The inverse of `f` (under gravity) into `out` (its n, m, angles and tension flag set by the
/// caller). Each round: the weight at the last answer's posture (the first: each hinge bent
/// evenly to its target, straight links), then the inverse with it held; done when the answer's
/// tension and voltages repeat to the inverse's own tolerance. With a tension given, the
/// rounds first run without it (the tension rule's midpoint: the first rounds' loads are
/// rough, and a given tension near an end of the interval would be refused on them), then
/// with it.
pub(super) fn solve<R: Real>(f: &Finger<R>, angles: &[R], tension: Option<R>, opts: &Options<R>, out: &mut PoseSolution<R>) -> Result<(), Error> {
    let p = f.params();
    let (n, m) = (p.n, p.m);
    let mut sub_q = [[[R::zero(); 3]; MAX_SUB]; MAX_JOINTS];
    for k in 0..n {
        for j in 0..m {
            sub_q[k][j][2] = angles[k] / R::from_u32(m as u32);
        }
    }
    let mut links = [[R::zero(); 3]; MAX_JOINTS];
    let mut prev: Option<(R, [R; MAX_JOINTS])> = None;
    let mut iterations = 0;
    let mut ask = None;
    for _ in 0..ROUNDS {
        let held = f.holding(&f.weight_at_posture(&sub_q, &links));
        if takes_general(&held) {
            general::solve(&held, None, angles, ask, opts, out)?;
        } else {
            *out = fast::solve(&held, angles, ask, opts, *out)?;
        }
        iterations += out.iterations;
        let now = (out.tension, out.volts);
        if let Some((pt, v)) = prev {
            // 1e-9 relative in f64, 2e-5 in f32 (the inverse's own tolerances, docs/inverse.md)
            let rel = R::from_f64(if R::EPS > 1e-10 { 2e-5 } else { 1e-9 });
            let same_p = (now.0 - pt).abs() <= rel * (R::one() + pt.abs());
            let same_v = (0..n).all(|k| (now.1[k] - v[k]).abs() <= rel * (R::one() + v[k].abs()));
            if same_p && same_v {
                if ask.is_none() && tension.is_some() {
                    // the loads have settled at the midpoint: now the tension asked
                    ask = tension;
                    prev = None;
                    sub_q = out.sub_q;
                    links = out.links;
                    continue;
                }
                out.iterations = iterations;
                out.tension_given = tension.is_some();
                return Ok(());
            }
        }
        prev = Some(now);
        sub_q = out.sub_q;
        links = out.links;
    }
    Err(Error::NotConverged { iterations, residual: f64::INFINITY })
}
