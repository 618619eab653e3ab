//! The paper's comparison (section III-B): the tension at which the finger without DE stacks
//! reaches the tip angle that the finger with stacks reaches at 1.0 N. The paper reports 0.631 N
//! for its geometry.

use finger_model::{Error, Finger, Method, Params};

/// Tip angle (rad) of a finger at tension `p` (N), stacks at 0 V.
fn tip_angle(f: &Finger<f64>, p: f64) -> Result<f64, Error> {
    Ok(f.solve(p, &[0.0; 3], Method::converged())?.tip().theta)
}

/// Bisection on tension for a target tip angle (the tip angle grows monotonically with it).
pub fn tension_for_tip_angle(f: &Finger<f64>, target: f64, hi: f64) -> Result<f64, Error> {
    let (mut lo, mut hi) = (0.0, hi);
    for _ in 0..200 {
        let mid = 0.5 * (lo + hi);
        if tip_angle(f, mid)? < target {
            lo = mid;
        } else {
            hi = mid;
        }
        if hi - lo < 1e-12 {
            break;
        }
    }
    Ok(0.5 * (lo + hi))
}

/// With the paper preset: (matching tension N, tip angle rad of the stacked finger at 1.0 N).
pub fn matching_tension() -> Result<(f64, f64), Error> {
    let with = Finger::new(Params::<f64>::paper())?;
    let without = Finger::new(Params::<f64>::paper().without_stacks())?;
    let target = tip_angle(&with, 1.0)?;
    Ok((tension_for_tip_angle(&without, target, 1.0)?, target))
}
