//! The end of the equilibrium branch under tension alone in fixed point (the firmware's fmax
//! on the Cortex-M3 image): bisection on the tension with the converged solve of
//! [`FixedFinger`], which follows the branch from 0 N by load continuation and is a typed
//! error past its end. Not the float model's `Finger::fmax` (branch tracking to the limit
//! point): the tension returned is the largest one the fixed-point solve was seen to hold.
use super::forward::FixedFinger;
use super::q::Nt;
use crate::error::Error;
use crate::finger::BranchEnd;

/// Search bound, N: half the Q22 range (a tension this large ends every finger's branch).
pub const SEARCH_BOUND_N: i32 = 256;
/// Bisection stop: the bracket within 2^-14 of its upper end (relative 6e-5).
const REL_SHIFT: u32 = 14;

/// Where the branch ends: the tension (N, Q22), the joint (1-based; 0 when the solve's error
/// does not name one) and how.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FixedBranchEnd {
    pub tension: Nt,
    pub joint: usize,
    pub kind: BranchEnd,
}

impl FixedFinger {
    /// fmax = max{P : the converged solve holds at P} by bisection on [0, SEARCH_BOUND_N]:
    /// `Contact` when the first failing tension met a contact, `LimitPoint` when its Newton
    /// did not converge (past a limit point), `SearchBound` when the bound itself solves.
    pub fn branch_end(&self) -> Result<FixedBranchEnd, Error> {
        let mut hi: Nt = super::q::Q(SEARCH_BOUND_N << 22);
        let mut err_hi = match self.solve(hi) {
            Ok(_) => return Ok(FixedBranchEnd { tension: hi, joint: 0, kind: BranchEnd::SearchBound }),
            Err(e) => e,
        };
        let mut lo = Nt::ZERO;
        while hi.0 - lo.0 > (hi.0 >> REL_SHIFT).max(1) {
            let mid: Nt = super::q::Q(lo.0 + (hi.0 - lo.0) / 2);
            match self.solve(mid) {
                Ok(_) => lo = mid,
                Err(e) => {
                    hi = mid;
                    err_hi = e;
                }
            }
        }
        let (joint, kind) = match err_hi {
            Error::Contact { joint, .. } => (joint, BranchEnd::Contact),
            _ => (0, BranchEnd::LimitPoint),
        };
        Ok(FixedBranchEnd { tension: lo, joint, kind })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Finger, Params};

    /// The fixed-point fmax never claims more than the float model's, and for the default model
    /// is close below it.
    #[test]
    fn branch_end_close_below_the_f64_fmax() {
        for p in [Params::<f64>::default(), Params { m: 1, plate: false, flex_links: false, ..Params::default() }] {
            let f = Finger::new(p).unwrap();
            for v in [[0.0; 3], [8000.0; 3]] {
                let want = f.fmax(&v).unwrap();
                let got = FixedFinger::new(&f, &v).unwrap().branch_end().unwrap();
                let t = got.tension.to_f64();
                assert!(t <= want.tension * (1.0 + 1e-3), "{p:?} {v:?}: {t} vs {}", want.tension);
                // the default model (the firmware's): within 3 % below (the fixed-point Newton
                // refuses the last steps before contact; the paper's m = 1 model ends far earlier)
                assert!(p.m == 1 || t >= want.tension * 0.97, "{v:?}: {t} vs {want:?}");
            }
        }
    }
}
