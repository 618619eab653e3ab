//! The model_contact target: the model target's contact force alone, its tensions on a scale
//! that needs no fmax (docs/reliability.md "The model target split").
//!
//! Input: the model target's parameter set and ops (`model::run_ops`: the same decoder, so the
//! model corpus seeds it), each op's tension P scaled from the tension that turns the softest
//! joint 1 rad linearly at its voltages, then the free tip's tension P0 from the same at 0 V
//! (`model::linear_tension`; the stop is the free tip at P0 and 0 V); the op byte only ends the
//! input.
//!
//! Invariants (the model target's for the contact):
//! - every call answers a typed error or a finite answer, never a panic;
//! - the ceiling is not negative nor NaN;
//! - a voltage refused by `de::check_voltage` is never answered;
//! - a contact answer's force and posture are finite, in equilibrium under its tip load
//!   (`Finger::equilibrium_residual` within `model::equilibrium_bound`), the tip on the stop
//!   (within 1e-4 of the length);
//! - an answer is on the branch the finger reaches: no hinge turned by more than 100° from the
//!   free posture at P0 (issue 55);
//! - the stop never pulls: the force's component along the tip's approach is not positive
//!   (within 5 % of |F| for the approach's finite difference).

use crate::model::{contact, linear_tension, run_ops};

/// Contacts per input: one (a contact refused at a limit point of the pinned equilibrium costs
/// up to half a second on far-off parameter sets; docs/reliability.md).
pub const MAX_OPS: usize = 1;

/// Runs one input; panics when an invariant breaks.
pub fn check(data: &[u8]) {
    run_ops(data, MAX_OPS, |c, _, v, refused, b| {
        let tension = b.scaled(linear_tension(&c.f, v));
        let p0 = b.scaled(linear_tension(&c.f, &vec![0.0; v.len()]));
        contact(&c.f, p0, tension, v, refused, c.len);
    });
}

/// The input's contact request as `check` makes it (the finger, P0, P, the voltages), or
/// `None` where the decoder ends first: for timing the requests (`examples/contact_cost.rs`).
pub fn request(data: &[u8]) -> Option<(finger_model::Finger<f64>, f64, f64, Vec<f64>)> {
    let mut out = None;
    run_ops(data, MAX_OPS, |c, _, v, _, b| {
        let tension = b.scaled(linear_tension(&c.f, v));
        let p0 = b.scaled(linear_tension(&c.f, &vec![0.0; v.len()]));
        out = Some((c.f, p0, tension, v.to_vec()));
    });
    out
}
