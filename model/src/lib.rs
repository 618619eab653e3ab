//! The variable-stiffness soft finger: a `no_std`, allocation-free model of the paper's
//! three-element iteration (n-FEM-NI) with docs/model.md's corrections.
//!
//! Modules, each one idea:
//! - [`real`]: the scalar (f32 on the target, f64 on the host), with explicitly chosen math.
//! - [`params`]: parameters, defaults, the paper preset, validation, access by name.
//! - [`hinge`]: elliptical notch thickness and compliance (Castigliano integrals).
//! - [`calibration`]: FE corrections to the sub-element compliances.
//! - [`material`]: the film's material law in time: cards, thinning, creep, ceilings.
//! - [`de`]: DE layer thinning, pull-in (33 %) limit, ceiling, stack stiffness.
//! - [`finger`]: joint equilibrium, posture, cable excursion, tip stiffness, two solvers.
//! - [`inverse`]: joint angles (and a tension) to tension and voltages; stiffness range; contact force.
//! - [`mat3`]: the 3x3 algebra they need.
//! - [`error`]: typed errors; nothing here panics or returns a non-finite result.
//!
//! docs/model.md puts each function next to the paper's equation and each correction.
#![no_std]
// One reviewed exception: the M4F's vsqrt.f32 (real.rs, `fpu_sqrt`). Nothing else is unsafe.
#![deny(unsafe_code)]

pub mod calibration;
pub mod de;
pub mod dual;
pub mod error;
pub mod finger;
#[cfg(feature = "fixed")]
pub mod fixed;
pub mod hinge;
pub mod inverse;
pub mod mat3;
pub mod material;
pub mod params;
pub mod real;
pub mod solve;

pub use calibration::Calibration;
pub use error::Error;
pub use finger::{BranchEnd, BranchLimit, Compliances, Finger, JointEquilibrium, JointStiffness, Method, Pose, Solution};
pub use inverse::{solve_pose, Contact, PoseSolution, StiffnessRange};
pub use params::{DeModulusRule, Params, MAX_JOINTS, MAX_SUB};
pub use real::Real;
