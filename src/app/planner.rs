//! The command side's model: the finger, and what is computed from it once per model and
//! kept: fmax at a set of setpoints (cached, keyed by the setpoints) and the branch table
//! (built at its first use). Every forward solve a handler plans with goes through here, so a
//! model change clears both in one place ([`Planner::set_finger`]).
//!
//! What it is not: the ceilings (`Commands::recompute`), the servo plan and the setpoint
//! checks (`Commands::plan_servo`, `plan_setpoints`: they read the board's parameters too),
//! the handlers.

use core::cell::Cell;

#[cfg(feature = "pose")]
use finger_model::Solution;
use finger_model::{BranchLimit, Error as ModelError, Finger};

use super::params::CHANNELS;
use super::solves::{fmax_of, forward, Solved};

pub(crate) struct Planner {
    finger: Finger<f32>,
    /// The board's cap, V (the inverse's `hv_fs`: `Commands::board_cap`).
    #[cfg(feature = "pose")]
    hv_fs: f32,
    /// `Finger::fmax` at the setpoints it was computed for, and how many times it ran.
    fmax_cache: Cell<Option<([f32; CHANNELS], Result<BranchLimit<f32>, ModelError>)>>,
    fmax_computed: Cell<u32>,
    /// The finger's branch table (`inverse::BranchTable`: `solve`, `pose`, `force` and fmax
    /// start from it), built at its first use after a model change (docs/inverse-cost.md has
    /// its cost). None inside for a finger without stacks.
    #[cfg(feature = "pose")]
    inv_table: core::cell::OnceCell<Option<finger_model::inverse::BranchTable<f32>>>,
}

impl Planner {
    /// `finger` under the board's cap `hv_fs` (V), nothing computed yet.
    pub(crate) fn new(finger: Finger<f32>, hv_fs: f32) -> Self {
        #[cfg(not(feature = "pose"))]
        let _ = hv_fs;
        Planner {
            finger,
            #[cfg(feature = "pose")]
            hv_fs,
            fmax_cache: Cell::new(None),
            fmax_computed: Cell::new(0),
            #[cfg(feature = "pose")]
            inv_table: core::cell::OnceCell::new(),
        }
    }

    pub(crate) fn finger(&self) -> &Finger<f32> {
        &self.finger
    }

    /// A new model (parameter or preset change): the fmax cache and the table no longer hold.
    pub(crate) fn set_finger(&mut self, f: Finger<f32>) {
        self.finger = f;
        self.fmax_cache.set(None);
        self.clear_table();
    }

    /// The ceilings changed: the branch table is built for the ceiling in force.
    pub(crate) fn clear_table(&mut self) {
        #[cfg(feature = "pose")]
        {
            self.inv_table = core::cell::OnceCell::new();
        }
    }

    /// The end of the equilibrium branch at the HV setpoints `volts` (`Finger::fmax`),
    /// cached: computed once per model and set of setpoints.
    pub(crate) fn fmax(&self, volts: &[f32; CHANNELS]) -> Result<BranchLimit<f32>, ModelError> {
        if let Some((key, r)) = self.fmax_cache.get() {
            if key == *volts {
                return r;
            }
        }
        #[cfg(feature = "pose")]
        let r = match self.branch_table() {
            Some(t) => t.fmax(volts),
            None => fmax_of(&self.finger, volts),
        };
        #[cfg(not(feature = "pose"))]
        let r = fmax_of(&self.finger, volts);
        self.fmax_cache.set(Some((*volts, r)));
        self.fmax_computed.set(self.fmax_computed.get() + 1);
        r
    }

    /// How many times `Finger::fmax` ran (the cache's misses), for the tests.
    pub(crate) fn fmax_evaluations(&self) -> u32 {
        self.fmax_computed.get()
    }

    /// The finger's branch table, built at its first use after a model change (None for a
    /// finger without stacks or under gravity, whose joints the table of the joints alone does
    /// not hold, or if it cannot be built: the full solves answer then).
    #[cfg(feature = "pose")]
    pub(crate) fn branch_table(&self) -> Option<&finger_model::inverse::BranchTable<f32>> {
        self.inv_table
            .get_or_init(|| {
                if self.finger.params().layers > 0 && !self.finger.has_weight() {
                    finger_model::inverse::BranchTable::new(&self.finger, &self.inverse_options()).ok()
                } else {
                    None
                }
            })
            .as_ref()
    }

    /// The inverse's options on this board: its ceiling is the one in force (HV full scale too).
    #[cfg(feature = "pose")]
    pub(crate) fn inverse_options(&self) -> finger_model::inverse::Options<f32> {
        finger_model::inverse::Options { hv_fs: Some(self.hv_fs), ..Default::default() }
    }

    /// The forward solve under tension alone at these voltages, handed to `use_it`: from the
    /// branch table when there is one (`BranchTable::solve_into`, into storage here: no copy
    /// of the solution; the full model's converged answer, Newton started at the table's guide
    /// holes), else the full solve (`forward`: f32, or fixed point on the M3).
    pub(crate) fn forward_with<T>(&self, p: f32, volts: &[f32; CHANNELS], use_it: impl FnOnce(&Solved) -> T) -> Result<T, ModelError> {
        #[cfg(feature = "pose")]
        if let Some(t) = self.branch_table() {
            let c = self.finger.compliances(volts)?;
            let mut sol = Solution::empty();
            t.solve_into(&c, p, &mut sol)?;
            return Ok(use_it(&sol));
        }
        forward(&self.finger, p, volts).map(|s| use_it(&s))
    }

    /// [`Planner::forward_with`] with the stacks at `thick_mm` now instead of relaxed at
    /// `volts` (`status`: the film creeps toward its voltages). The M3 image solves at the
    /// voltages (its fixed-point path takes no thickness).
    pub(crate) fn forward_now<T>(
        &self,
        p: f32,
        volts: &[f32; CHANNELS],
        thick_mm: &[f32; CHANNELS],
        use_it: impl FnOnce(&Solved) -> T,
    ) -> Result<T, ModelError> {
        #[cfg(m3)]
        {
            let _ = thick_mm;
            self.forward_with(p, volts, use_it)
        }
        #[cfg(not(m3))]
        {
            let c = self.finger.compliances_at_thickness(volts, thick_mm)?;
            #[cfg(feature = "pose")]
            if let Some(t) = self.branch_table() {
                let mut sol = Solution::empty();
                t.solve_into(&c, p, &mut sol)?;
                return Ok(use_it(&sol));
            }
            self.finger.solve_with(&c, p, [0.0; 2], finger_model::Method::converged()).map(|s| use_it(&s))
        }
    }
}
