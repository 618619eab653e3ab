//! Fixed-point forward model for cores without an FPU (the Cortex-M3 image).
//!
//! What it is: the converged joint equilibrium under cable tension alone (`Finger::solve`
//! with no tip load: the march, Newton per joint, the chain, the excursion) in 32-bit words
//! with a Q format per quantity ([`q`]) and 32x32 -> 64 products, trig by polynomial
//! ([`trig`]). The compliances are computed once per voltage set in the float model and
//! converted ([`FixedFinger::new`]), each entry with its own scale.
//! And the inverse ([`inverse`]: each joint's stack thickness for target angles at a given
//! tension or at the float inverse's tension rule, compliances interpolated from a table built
//! once, or computed per evaluation without the table), fmax by following each joint's branch
//! ([`branch_end`]), the tip stiffness from the converged state (its J C Jᵀ in float).
//! What it is not: the tip-loaded solve, the paper's stepping, contact. Error budget and
//! measurements: docs/fixed-point.md.

pub mod branch_end;
pub mod forward;
pub mod inverse;
pub mod q;
pub mod trig;

pub use branch_end::FixedBranchEnd;
pub use forward::{FixedFinger, FixedSolution};
pub use inverse::{FixedInverse, FixedInverseDirect, FixedPoseSolution};
