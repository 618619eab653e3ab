//! The model_forward target: the model target's forward solve alone, its tension on a scale
//! that needs no fmax (docs/reliability.md "The model target split").
//!
//! Input: the model target's parameter set and ops (`model::run_ops`: the same decoder, so the
//! model corpus seeds it), each op's tension `Bytes::scaled` from the tension
//! that turns the softest joint 1 rad linearly at its voltages (`model::linear_tension`:
//! 2^-6..2^6 of it, or 0, negative, NaN, infinities, extremes, raw bits); the op byte only
//! ends the input.
//!
//! Invariants (the model target's for the forward):
//! - every call answers a typed error or a finite answer, never a panic;
//! - the ceiling is not negative nor NaN;
//! - an answer's voltages are 0 or below the ceiling, and a voltage refused by
//!   `de::check_voltage` (negative, not finite, at/past the ceiling) is never answered;
//! - a forward answer is in equilibrium (`Finger::equilibrium_residual` within
//!   `model::equilibrium_bound`).

use crate::model::{forward, linear_tension, run_ops, MAX_OPS};

/// Runs one input; panics when an invariant breaks.
pub fn check(data: &[u8]) {
    run_ops(data, MAX_OPS, |c, _, v, refused, b| {
        let tension = b.scaled(linear_tension(&c.f, v));
        forward(&c.f, tension, v, refused);
    });
}
