//! The end of the equilibrium branch under tension alone in fixed point (the firmware's fmax
//! on the Cortex-M3 image): each distinct joint's branch followed from 0 N in tension
//! (`FixedFinger::follow_branch`) to the refusal that ends it, the lowest end a margin below,
//! checked by the whole solve. Not the float model's `Finger::fmax` (its span and tangent
//! secants): the tension returned is one the fixed-point branch was seen to hold.
use super::forward::{FixedFinger, MarchError};
use super::q::{Mm, Nt, Q};
use crate::error::Error;
use crate::finger::BranchEnd;
use crate::params::MAX_JOINTS;

/// Search bound, N: 7/8 of the Q22 range.
pub const SEARCH_BOUND_N: i32 = 448;
/// The end returned is below the last tension held by 2^-12 (2.4e-4) of it.
const MARGIN_SHIFT: u32 = 12;
/// Stop: the branch's step, and the fallback bisection's bracket, within 2^-14 of its upper end (relative 6e-5).
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
    /// fmax: per distinct joint, its branch followed from 0 N ([`FixedFinger::follow_branch`],
    /// each later joint only up to the end found so far) to 2^-14 relative; the lowest end,
    /// `Contact` or `LimitPoint` from the refusal that ended it, `SearchBound` when every joint
    /// holds the bound. That tension is then checked by the whole solve (the chain, the spans),
    /// each joint's Newton from its branch's last hole; refused there, bisection below it on
    /// that solve (a cold solve's refusals are scattered near an m = 1 stall: not monotone).
    pub fn branch_end(&self) -> Result<FixedBranchEnd, Error> {
        let mut end = FixedBranchEnd { tension: Q(SEARCH_BOUND_N << 22), joint: 0, kind: BranchEnd::SearchBound };
        // each joint's last hole on its branch: the check's Newton starts there
        let mut holes = [[Mm::ZERO; 2]; MAX_JOINTS];
        for k in 0..self.n {
            if self.same_as_prev[k] {
                holes[k] = holes[k - 1];
                continue;
            }
            let (p, hole, why) = self.follow_branch(k, end.tension, REL_SHIFT);
            holes[k] = hole;
            if let Some(e) = why {
                let kind = if matches!(e, MarchError::Contact) { BranchEnd::Contact } else { BranchEnd::LimitPoint };
                end = FixedBranchEnd { tension: p, joint: k + 1, kind };
            }
        }
        // the margin: below the end by more than the fixed-point span's error there
        end.tension = Q(end.tension.0 - (end.tension.0 >> MARGIN_SHIFT));
        let mut hi = end.tension;
        let mut err_hi = match self.solve_from(hi, Some(&holes)) {
            Ok(_) => return Ok(end),
            Err(e) => e,
        };
        let mut lo = Nt::ZERO;
        while hi.0 - lo.0 > (hi.0 >> REL_SHIFT).max(1) {
            let mid: Nt = Q(lo.0 + (hi.0 - lo.0) / 2);
            match self.solve_from(mid, Some(&holes)) {
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
    use crate::{Finger, Method, Params};

    /// The fixed-point fmax is on the safe side (the f64 model's converged solve holds there)
    /// and close below the f64 `Finger::fmax`: for the firmware's model within 0.1 % (the margin
    /// of 2^-12 and the fixed-point span's error near contact), for the m = 1 models (the
    /// paper's hinge, `preset paper`) within 5 % (their Newton stalls at the hole's resolution
    /// short of contact: docs/fixed-point.md), at 0 V, 8 kV and mixed voltages.
    #[test]
    fn branch_end_close_below_the_f64_fmax() {
        let m1 = Params { m: 1, plate: false, flex_links: false, ..Params::default() };
        for (p, band) in [(Params::<f64>::default(), 1e-3), (m1, 0.05), (Params::paper(), 0.05)] {
            let f = Finger::new(p).unwrap();
            for v in [[0.0; 3], [8000.0; 3], [0.0, 4000.0, 9000.0]] {
                let want = f.fmax(&v).unwrap();
                let got = FixedFinger::new(&f, &v).unwrap().branch_end().unwrap();
                let t = got.tension.to_f64();
                assert!(f.solve(t, &v, Method::converged()).is_ok(), "m={} {v:?}: {t} past the f64 branch ({want:?})", p.m);
                assert!(t >= want.tension * (1.0 - band), "m={} {v:?}: {t} vs {want:?}", p.m);
                if p.m > 1 {
                    assert!(t <= want.tension, "{v:?}: {t} vs {want:?}");
                    assert_eq!((got.kind, got.joint), (want.kind, want.joint), "{v:?}");
                }
            }
        }
    }
}
