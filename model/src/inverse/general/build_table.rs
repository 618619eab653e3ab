//! The branch table's build (`BranchTable::new`): each sample the general path's
//! `hold_tension`, continued from the sample before, ending where the branch does. Here, in
//! the general path, so that the table (inverse/table.rs) imports nothing of the solver that
//! reads it. What it is not: the table's readings (table.rs).

use super::*;
use crate::inverse::table::{zero_grid, TABLE_LEN, TABLE_STEP_DEG};

impl<R: Real> BranchTable<R> {
    /// Build the table for finger `f` and the inverse options `opts` (their `top` sets the
    /// softest end). Fails for a finger without stacks (nothing to tabulate: its inverse is
    /// one root per joint) and for options the inverse refuses.
    #[inline(never)]
    pub fn new(f: &Finger<R>, opts: &Options<R>) -> Result<Self, Error> {
        crate::inverse::check_options(opts)?;
        let p = f.params();
        if p.layers == 0 {
            return Err(Error::Input { input: "table", reason: "a finger without stacks has no branch table" });
        }
        let mut g = Gen::new(f, opts)?;
        // samples eight times tighter than a solve's tolerance: the ends read off the table
        // start step 4, whose first march then lands inside that tolerance
        g.tighten(R::from_f64(0.125));
        let (t0, t_top, v_top) = g.stack_ends(opts)?;
        let comp = [g.comp(t_top)?, g.comp(t0)?];
        let t_mid = (t_top + t0) / R::from_f64(2.0);
        let c_mid = g.comp(t_mid)?;
        let slope0 = [g.slope0(&comp[0]), g.slope0(&comp[1])];
        let step = R::from_f64(TABLE_STEP_DEG.to_radians());
        let lh = p.hinge_len();
        let mut t = BranchTable {
            finger: *f,
            opts: *opts,
            thickness: [t_top, t0, t_mid],
            v_top,
            volts: de::Stack::new(p),
            comp,
            slope0,
            step,
            len: [1; 3],
            x: [[[R::zero(), lh, p.e]; TABLE_LEN]; 3],
            angle_cubics: [[[[R::zero(); 4]; 3]; 3]; TABLE_LEN],
            grid: zero_grid(),
            dp: R::zero(),
            inv_dp: R::zero(),
            grid_len: 0,
            grid_top: R::zero(),
        };
        let mut scratch = [[R::zero(); 3]; MAX_SUB];
        for e in 0..3 {
            let th = t.thickness[e];
            let (c, s_lin) = if e < 2 { (&t.comp[e], t.slope0[e]) } else { (&c_mid, g.slope0(&c_mid)) };
            let mut jac: Option<Mat3<R>> = None;
            let mut slope = s_lin;
            for i in 1..TABLE_LEN {
                let theta = step * R::from_u32(i as u32);
                let xs = &t.x[e];
                // linear extrapolation from the two samples before (none for the first)
                let ex = |c: usize| xs[i - 1][c] + xs[i - 1][c] - xs[i - 2][c];
                let hint = if i > 1 { Some((ex(0), [ex(1), ex(2)])) } else { None };
                let Ok(h) = g.hold_tension(1, theta, c, th, s_lin, hint, jac, Some(slope), &mut scratch) else {
                    break;
                };
                if !(h.tension > t.x[e][i - 1][0]) {
                    // past a limit point the branch turns back: the table ends before it
                    break;
                }
                t.x[e][i] = [h.tension, h.st.hole[0], h.st.hole[1]];
                t.len[e] = i + 1;
                jac = h.jac.or(jac);
                slope = h.slope;
            }
        }
        t.build_angle_cubics();
        t.build_tension_grid();
        Ok(t)
    }
}
