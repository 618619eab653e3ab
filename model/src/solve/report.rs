//! One options type and one convergence/error report for every iterative solve.

use crate::real::Real;

/// Tolerances and limits of an iterative solve.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SolveOptions<R> {
    /// Converged when |r| <= tol (the residual's own unit).
    pub tol: R,
    /// The resolution of the residual in the scalar type: a line search that cannot lower |r|
    /// below it has converged as far as the type can.
    pub floor: R,
    /// Iterations (Jacobians) at most.
    pub max_iter: u32,
    /// Step halvings per line search.
    pub max_halvings: u32,
}

impl<R: Real> SolveOptions<R> {
    pub fn new(tol: R, floor: R, max_iter: u32) -> Self {
        SolveOptions { tol, floor, max_iter, max_halvings: 12 }
    }
}

/// A solve that reached its tolerance (or the scalar's resolution).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Converged<R> {
    pub iterations: u32,
    /// |r| at the answer.
    pub residual: R,
}

/// Why a solve stopped without an answer. `E` is the caller's own refusal (the residual could
/// not be evaluated: contact, a singular march, ...).
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Failure<E> {
    /// The residual refused at the start point.
    Domain(E),
    /// The Jacobian was singular.
    Singular { iterations: u32 },
    /// No step along the Newton direction lowered |r|; `last` is the refusal met on the way,
    /// if any.
    Stalled { iterations: u32, residual: f64, last: Option<E> },
    /// `max_iter` used up.
    MaxIter { iterations: u32, residual: f64 },
}

impl<E> Failure<E> {
    pub fn iterations(&self) -> u32 {
        match *self {
            Failure::Domain(_) => 0,
            Failure::Singular { iterations } | Failure::Stalled { iterations, .. } | Failure::MaxIter { iterations, .. } => iterations,
        }
    }
    /// The caller's refusal behind this failure, if one was met.
    pub fn refusal(&self) -> Option<&E> {
        match self {
            Failure::Domain(e) => Some(e),
            Failure::Stalled { last, .. } => last.as_ref(),
            _ => None,
        }
    }
}
