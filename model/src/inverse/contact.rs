//! The contact force (the paper's second conclusion): the tip stops at a point X0, the free
//! tip at (P0, V0); at (P, V) the load F the stop exerts to hold the tip at X0. The pinned
//! equilibrium is reached by continuation from the free posture (`Finger::pinned_tip`,
//! finger/pinned.rs), so every request inside the branch answers or is refused with a typed
//! reason: a tension past fmax (`ForceLimit`, at P0 with V0 or at P with V), the links
//! touching on the way (`Contact`), the stop not holdable (`LimitPoint` of the pinned
//! equilibrium), the stop pulling on the tip (`PullingStop`: along the way the stop's force
//! has a component along the tip's approach, the direction the free tip moves in as the
//! tension rises at (P0, V0): the tip leaves it). F is the force the object exerts on the tip;
//! the finger presses with -F. The tip is pinned (no slip).

use crate::error::Error;
use crate::finger::{BranchLimit, Finger, Method, Solution};
use crate::real::Real;

/// The contact force of a tip held at a point.
#[derive(Clone, Copy, Debug)]
pub struct Contact<R> {
    /// The contact point (base frame), mm: the free tip at (P0, V0).
    pub point: [R; 2],
    /// The force the object exerts on the tip (base frame), N. The finger presses with -force.
    pub force: [R; 2],
    /// The loaded equilibrium that holds the tip at the point.
    pub solution: Solution<R>,
    /// Newton iterations on the force.
    pub iterations: u32,
}

impl<R: Real> Contact<R> {
    /// |force|, N.
    pub fn magnitude(&self) -> R {
        (self.force[0].sq() + self.force[1].sq()).sqrt()
    }
}

/// The contact force: the tip stops at the free tip of (`p0`, `volts0`); at tension `p` and
/// `volts` the tip load that holds it there (see the module header).
pub fn contact_force<R: Real>(f: &Finger<R>, p0: R, volts0: &[R], p: R, volts: &[R]) -> Result<Contact<R>, Error> {
    for (t, name) in [(p0, "P0"), (p, "P")] {
        if !t.is_finite() {
            return Err(Error::NonFinite { input: name });
        }
        if t < R::zero() {
            return Err(Error::Input { input: name, reason: "a cable cannot push: tension must be >= 0" });
        }
    }
    let past = |t: R, end: BranchLimit<R>| (t > end.tension).then(|| Error::ForceLimit { tension: t.to_f64(), fmax: end.tension.to_f64() });
    let free0 = if f.weights().is_none() {
        // fmax once where both ends have the same voltages
        let end0 = f.fmax(volts0)?;
        if let Some(e) = past(p0, end0) {
            return Err(e);
        }
        let end = if volts0 == volts { end0 } else { f.fmax(volts)? };
        if let Some(e) = past(p, end) {
            return Err(e);
        }
        f.solve(p0, volts0, Method::converged())?
    } else {
        // under gravity fmax is where the coupled solve stops holding (to 1e-4: `Finger::fmax`),
        // a search of some twenty solves: a tension the solve holds is within it, and fmax is
        // found only to quote it for one it does not hold
        let within = |t: R, v: &[R]| -> Result<Result<Solution<R>, Error>, Error> {
            match f.solve(t, v, Method::converged()) {
                Ok(s) => Ok(Ok(s)),
                Err(e) => match past(t, f.fmax(v)?) {
                    Some(limit) => Err(limit),
                    None => Ok(Err(e)),
                },
            }
        };
        let free0 = within(p0, volts0)??;
        // below fmax but not held: the pinned continuation's own refusal follows
        within(p, volts)?.ok();
        free0
    };
    let pin = f.pinned_tip(&free0, p, volts)?;
    let point = [free0.tip().x, free0.tip().y];
    Ok(Contact { point, force: pin.force, solution: pin.solution, iterations: pin.iterations })
}
