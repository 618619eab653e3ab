//! The model_fmax target: fmax, and the forward at fractions of it (docs/reliability.md "The
//! model target split").
//!
//! Input: the model target's parameter set and ops (`model::run_ops`: the same decoder, so the
//! model corpus seeds it), each op's tension a fraction of fmax at its voltages as the model
//! target reads it (0 to 1.2 fmax, fmax, fmax x (1 -+ 1e-12), or special values; 1 N's
//! fractions where fmax refuses the voltages); the op byte only ends the input.
//!
//! Invariants (the model target's for fmax, and the forward's near fmax's end):
//! - every call answers a typed error or a finite answer, never a panic;
//! - the ceiling is not negative nor NaN;
//! - fmax is finite and not negative, and never answered at voltages `de::check_voltage`
//!   refuses;
//! - a forward answer at a fraction of fmax is in equilibrium (`equilibrium_residual` within
//!   `model::equilibrium_bound`), its voltages 0 or below the ceiling.

use crate::model::{checked_fmax, forward, run_ops, MAX_OPS};

/// Runs one input; panics when an invariant breaks.
pub fn check(data: &[u8]) {
    run_ops(data, MAX_OPS, |c, _, v, refused, b| {
        let fmax = checked_fmax(c, v, refused);
        let tension = b.fraction(fmax.unwrap_or(1.0));
        forward(&c.f, tension, v, refused);
    });
}
