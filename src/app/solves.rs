//! The forward solves behind the console's answers: the f32 model's; on the Cortex-M3 image
//! the fixed-point model's (`super::m3`). One name each whatever the build: [`Solved`],
//! [`forward`], [`fmax_of`].

#[cfg(not(m3))]
use finger_model::{BranchLimit, Error as ModelError, Finger, Method, Solution};

#[cfg(not(m3))]
use super::params::CHANNELS;

#[cfg(not(m3))]
pub(crate) type Solved = Solution<f32>;
#[cfg(not(m3))]
#[inline(always)]
pub(crate) fn forward(f: &Finger<f32>, p: f32, volts: &[f32; CHANNELS]) -> Result<Solved, ModelError> {
    f.solve(p, volts, Method::converged())
}
#[cfg(not(m3))]
#[inline(always)]
pub(crate) fn fmax_of(f: &Finger<f32>, volts: &[f32; CHANNELS]) -> Result<BranchLimit<f32>, ModelError> {
    f.fmax(volts)
}
#[cfg(m3)]
pub(crate) use super::m3::{fmax_of, forward, forward_stiffness, Solved};
