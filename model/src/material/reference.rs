//! The law in time, integrated finely: the host's f64 truth for the per-tick steppers.
//! Classical RK4 on the branch flow with the film balance solved at every stage (the
//! thickness follows the branches exactly); the voltage is held over the step.
//!
//! What it is not: the firmware's stepper (`Relaxation`), which holds the thickness over a tick.

use super::{branch_flow, ratio_at_voltage, StackLaw, StackState, MAX_BRANCHES};
use crate::error::Error;
use crate::real::Real;

/// The branch flow `da_i/dt = (1/s - s^2 a_i^3) / (3 tau_i)` with s from the film balance at
/// `volts`; `s_guess` warm-starts the balance and becomes its root.
fn flow<R: Real>(law: &StackLaw<R>, a: &[R; MAX_BRANCHES], volts: R, s_guess: &mut R) -> Result<[R; MAX_BRANCHES], Error> {
    let s = ratio_at_voltage(law, a, volts, *s_guess)?;
    *s_guess = s;
    let mut d = [R::zero(); MAX_BRANCHES];
    for i in 0..law.branches.min(MAX_BRANCHES) {
        d[i] = branch_flow(R::one() / s, s * s, a[i]) / (R::from_f64(3.0) * law.tau[i]);
    }
    Ok(d)
}

/// One tick as the firmware's: the thickness now at `volts` (`state.s`), then the branches
/// advanced over `dt_s` by `substeps` RK4 steps at the held voltage.
pub fn advance_reference<R: Real>(law: &StackLaw<R>, state: &mut StackState<R>, volts: R, dt_s: R, substeps: u32) -> Result<(), Error> {
    state.s = ratio_at_voltage(law, &state.a, volts, state.s)?;
    let h = dt_s / R::from_u32(substeps.max(1));
    let half = R::from_f64(0.5);
    let mut a = state.a;
    let mut s = state.s;
    let add = |a: &[R; MAX_BRANCHES], k: &[R; MAX_BRANCHES], c: R| {
        let mut o = *a;
        for i in 0..MAX_BRANCHES {
            o[i] += c * k[i];
        }
        o
    };
    for _ in 0..substeps.max(1) {
        let k1 = flow(law, &a, volts, &mut s)?;
        let k2 = flow(law, &add(&a, &k1, half * h), volts, &mut s)?;
        let k3 = flow(law, &add(&a, &k2, half * h), volts, &mut s)?;
        let k4 = flow(law, &add(&a, &k3, h), volts, &mut s)?;
        for i in 0..MAX_BRANCHES {
            a[i] += h / R::from_f64(6.0) * (k1[i] + R::from_f64(2.0) * (k2[i] + k3[i]) + k4[i]);
        }
    }
    state.a = a;
    Ok(())
}
