//! The solver layer every solve in the model uses: one options type ([`SolveOptions`]), one
//! report ([`Converged`], [`Failure`]), and the methods, one a file:
//! - [`lu`]: dense LU with partial pivoting, generic over the scalar and the size;
//! - [`newton`]: damped Newton with a backtracking line search on |r|;
//! - [`broyden`]: Broyden's rank-one update on a Newton step (no Jacobian after the first);
//! - [`bracket`]: a safeguarded bracket (Illinois) for a scalar root, and the boundary of a
//!   feasible set (where a solve stops existing);
//! - [`continuation`]: a parameter from 0 to 1 in steps that double on success and halve on
//!   failure.
//!
//! What it is not: physics. The callers (forward, inverse, contact) own their equations and
//! map a [`Failure`] to the model's typed [`crate::Error`]. No allocation; sizes are const
//! generics with a run-time `dim <= N`.

pub mod bracket;
pub mod broyden;
pub mod continuation;
pub mod lu;
pub mod newton;
mod report;

pub use report::{Converged, Failure, SolveOptions};
