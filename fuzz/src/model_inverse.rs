//! The model_inverse target: the model target's inverse alone, its tension on a scale that
//! needs no fmax (docs/reliability.md "The model target split").
//!
//! Input: the model target's parameter set and ops (`model::run_ops`: the same decoder, so the
//! model corpus seeds it), each op's tension scaled from the tension that turns the softest
//! joint 1 rad linearly at its voltages (`model::linear_tension`, as model_forward's); the
//! forward's posture at that tension and voltages is the inverse's target, with its tension
//! given or free (the tension's last bit); the op byte only ends the input.
//!
//! Invariants (the model target's for the inverse):
//! - every call answers a typed error or a finite answer, never a panic;
//! - the ceiling is not negative nor NaN;
//! - an inverse answer's tension is finite and >= 0, its voltages 0 or below the ceiling;
//! - the inverse gives back its angles: the forward of its tension and voltages answers, each
//!   joint within 1e-6 rad of the target.

use crate::model::{inverse, linear_tension, run_ops, MAX_OPS};

/// Runs one input; panics when an invariant breaks.
pub fn check(data: &[u8]) {
    run_ops(data, MAX_OPS, |c, _, v, _, b| {
        let tension = b.scaled(linear_tension(&c.f, v));
        inverse(&c.f, tension, v, c.len);
    });
}
