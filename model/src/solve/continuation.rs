//! Continuation in a parameter λ from 0 to 1 with step control: a step that succeeds doubles
//! the next, one that fails is halved and retried from the last accepted λ, down to a
//! smallest step.

use crate::real::Real;

/// What a step tells the controller.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Step<E> {
    /// Halve the step and retry.
    Retry(E),
    /// End the continuation (a budget is spent, or the failure cannot be cured by a shorter step).
    Stop(E),
}

/// Run `step(from, to)` from λ = 0 to 1, starting with `first` and never below `min_step`.
/// Returns the accepted steps, or the λ reached and the last refusal (`stalled` when λ
/// cannot advance in the scalar type).
pub fn run<R: Real, E: Copy>(first: R, min_step: R, stalled: E, step: &mut dyn FnMut(R, R) -> Result<(), Step<E>>) -> Result<u32, (R, E)> {
    let one = R::one();
    let mut done = R::zero();
    let mut h = first.min(one);
    let mut accepted = 0u32;
    loop {
        let to = (done + h).min(one);
        if !(to > done) {
            return Err((done, stalled));
        }
        match step(done, to) {
            Ok(()) => {
                accepted += 1;
                done = to;
                if done >= one {
                    return Ok(accepted);
                }
                h = h + h;
            }
            Err(Step::Stop(e)) => return Err((done, e)),
            Err(Step::Retry(e)) => {
                h /= R::from_f64(2.0);
                if h < min_step {
                    return Err((done, e));
                }
            }
        }
    }
}
