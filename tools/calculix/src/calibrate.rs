//! Calibration: the factors of `finger_model::Calibration` from linear FE unit loads on one
//! element (hinge + link, `element_compliance`), so that the model's small-load element
//! compliance equals the FE's.
//!
//! - Hinge (no stack): the model's element compliance is linear in the four hinge factors,
//!   `C_el(f) = C_link + Σ_i f_i B_i`; the four entries x-Fx, y-Fy, y-M, θ-M are matched exactly
//!   (a 4x4 linear solve).
//! - Stack, at each of a few thicknesses: with the hinge factors fixed, the stack's EA and EI
//!   factors (Newton, 2x2) match θ-M and θ-Fx (the axial-bending coupling the stack's offset
//!   gives, which the cable's compression turns into rotation). A line in t through them (least
//!   squares) is what the model carries.

use crate::ccx::{FeError, Kind};
use crate::mesh::Density;
use finger_model::mat3::Mat3;
use finger_model::material::{Breakdown, Card};
use finger_model::{de, Calibration, Finger, Method, Params};

/// The model's element compliance (hinge, with its stack at thickness `stack_mm` (0: none), and
/// link) at zero load and without gravity: `Finger::tip_compliance` of a one-joint finger.
pub fn model_element_compliance(p: &Params<f64>, cal: &Calibration<f64>, stack_mm: f64) -> Result<Mat3<f64>, String> {
    // the supply, margin and breakdown field do not enter the mechanics: raised so that every
    // thickness down to near the 33 % limit can be evaluated (one leaked card per call: a
    // host tool's handful of calls)
    let card: &'static Card = Box::leak(Box::new(Card { breakdown: Breakdown { field0_v_per_um: 1e9 }, ..*p.card }));
    // without gravity: the FE's unit loads carry no body load, so the calibration must not
    // absorb it (docs/fidelity-fe.md "Under its own weight")
    let q = Params { n: 1, layers: if stack_mm > 0.0 { p.layers } else { 0 }, v_supply: 1e5, margin: 0.999, card, grav: 0.0, ..*p };
    let f = Finger::with_calibration(q, *cal).map_err(|e| e.to_string())?;
    let v = if stack_mm > 0.0 { de::voltage_for_thickness(&q, 1, stack_mm).map_err(|e| e.to_string())? } else { 0.0 };
    let c = f.compliances(&[v]).map_err(|e| e.to_string())?;
    let s = f.solve_with(&c, 0.0, [0.0; 2], Method::converged()).map_err(|e| e.to_string())?;
    Ok(f.tip_compliance(&c, &s))
}

/// One thickness's calibration case.
#[derive(Clone, Debug)]
pub struct StackCase {
    pub thickness_mm: f64,
    pub fe: Mat3<f64>,
    /// (EA, EI) factors matching this thickness alone.
    pub factors: [f64; 2],
}

/// The calibration and the FE data it comes from.
#[derive(Clone, Debug)]
pub struct CalibrationRun {
    pub kind: Kind,
    pub density: Density,
    pub cal: Calibration<f64>,
    pub fe_hinge: Mat3<f64>,
    pub stacks: Vec<StackCase>,
}

fn solve4(mut a: [[f64; 4]; 4], mut b: [f64; 4]) -> Option<[f64; 4]> {
    for c in 0..4 {
        let piv = (c..4).max_by(|&i, &j| a[i][c].abs().total_cmp(&a[j][c].abs()))?;
        if a[piv][c].abs() < 1e-300 {
            return None;
        }
        a.swap(c, piv);
        b.swap(c, piv);
        for r in c + 1..4 {
            let f = a[r][c] / a[c][c];
            for k in c..4 {
                a[r][k] -= f * a[c][k];
            }
            b[r] -= f * b[c];
        }
    }
    let mut x = [0.0; 4];
    for i in (0..4).rev() {
        let s: f64 = (i + 1..4).map(|k| a[i][k] * x[k]).sum();
        x[i] = (b[i] - s) / a[i][i];
    }
    Some(x)
}

const ENTRIES: [(usize, usize); 4] = [(0, 0), (1, 1), (1, 2), (2, 2)];

/// Hinge factors from the FE element compliance without a stack.
pub fn hinge_factors(p: &Params<f64>, fe: &Mat3<f64>) -> Result<[f64; 4], String> {
    let ones = Calibration::<f64>::none();
    let c1 = model_element_compliance(p, &ones, 0.0)?;
    let mut basis = [[[0.0; 3]; 3]; 4];
    for (i, b) in basis.iter_mut().enumerate() {
        let mut cal = ones;
        // linear in the factors: a small step keeps every sub-element matrix definite
        let h = 0.01;
        cal.hinge[i] = 1.0 + h;
        let c2 = model_element_compliance(p, &cal, 0.0)?;
        for r in 0..3 {
            for c in 0..3 {
                b[r][c] = (c2[r][c] - c1[r][c]) / h;
            }
        }
    }
    // C_link = C(1) - Σ B_i
    let mut a = [[0.0; 4]; 4];
    let mut rhs = [0.0; 4];
    for (e, &(r, c)) in ENTRIES.iter().enumerate() {
        let link = c1[r][c] - basis.iter().map(|b| b[r][c]).sum::<f64>();
        rhs[e] = fe[r][c] - link;
        for i in 0..4 {
            a[e][i] = basis[i][r][c];
        }
    }
    solve4(a, rhs).ok_or_else(|| "singular hinge calibration".to_string())
}

/// Stack (EA, EI) factors at one thickness (hinge factors fixed): Newton on θ-M and θ-Fx.
pub fn stack_factors(p: &Params<f64>, hinge: [f64; 4], t: f64, fe: &Mat3<f64>) -> Result<[f64; 2], String> {
    let at = |g: [f64; 2]| -> Result<[f64; 2], String> {
        let cal = Calibration { hinge, stack_axial: [g[0], 0.0], stack_bending: [g[1], 0.0] };
        let c = model_element_compliance(p, &cal, t)?;
        Ok([c[2][2] / fe[2][2] - 1.0, (c[2][0] - fe[2][0]) / fe[2][2].abs()])
    };
    let mut g = [1.0, 1.0];
    for _ in 0..30 {
        let r = at(g).map_err(|e| format!("stack factors at t = {t} mm: EA x {:.4}, EI x {:.4} on the way to the FE's: {e} (the model's range; the beam stack cannot be calibrated to the FE there)", g[0], g[1]))?;
        if r[0].abs() < 1e-10 && r[1].abs() < 1e-10 {
            return Ok(g);
        }
        let h = 1e-6;
        let ra = at([g[0] * (1.0 + h), g[1]])?;
        let rb = at([g[0], g[1] * (1.0 + h)])?;
        let j = [[(ra[0] - r[0]) / (g[0] * h), (rb[0] - r[0]) / (g[1] * h)], [(ra[1] - r[1]) / (g[0] * h), (rb[1] - r[1]) / (g[1] * h)]];
        let det = j[0][0] * j[1][1] - j[0][1] * j[1][0];
        if det.abs() < 1e-300 {
            return Err("singular stack calibration".into());
        }
        let dx = [(r[0] * j[1][1] - r[1] * j[0][1]) / det, (j[0][0] * r[1] - j[1][0] * r[0]) / det];
        g = [(g[0] - dx[0]).clamp(0.1 * g[0], 10.0 * g[0]), (g[1] - dx[1]).clamp(0.1 * g[1], 10.0 * g[1])];
    }
    Err(format!("stack calibration at t = {t} mm did not converge"))
}

/// The stack thicknesses calibrated: N_L z0 (0 V), 0.875 and 0.75 of it (the stable branch
/// ends at 2/3).
pub fn thicknesses(p: &Params<f64>) -> Vec<f64> {
    let t0 = p.layers as f64 * p.z0;
    vec![t0, 0.875 * t0, 0.75 * t0]
}

/// The whole calibration for a parameter set (its `layers`, `z0` give the stack's range).
pub fn run(p: &Params<f64>, kind: Kind, d: &Density) -> Result<CalibrationRun, Box<dyn std::error::Error>> {
    let fe_hinge = crate::element_compliance(p, 0.0, kind, d)?;
    let hinge = hinge_factors(p, &fe_hinge)?;
    let mut stacks = Vec::new();
    if p.layers > 0 {
        for t in thicknesses(p) {
            let fe = crate::element_compliance(p, t, kind, d)?;
            let factors = stack_factors(p, hinge, t, &fe)?;
            stacks.push(StackCase { thickness_mm: t, fe, factors });
        }
    }
    // lines g = g0 + g1 t through the per-thickness factors (least squares)
    let line = |k: usize| -> [f64; 2] {
        let n = stacks.len() as f64;
        if stacks.is_empty() {
            return [1.0, 0.0];
        }
        if stacks.len() == 1 {
            return [stacks[0].factors[k], 0.0];
        }
        let mt = stacks.iter().map(|s| s.thickness_mm).sum::<f64>() / n;
        let mg = stacks.iter().map(|s| s.factors[k]).sum::<f64>() / n;
        let sxy: f64 = stacks.iter().map(|s| (s.thickness_mm - mt) * (s.factors[k] - mg)).sum();
        let sxx: f64 = stacks.iter().map(|s| (s.thickness_mm - mt).powi(2)).sum();
        let g1 = sxy / sxx;
        [mg - g1 * mt, g1]
    };
    let cal = Calibration { hinge, stack_axial: line(0), stack_bending: line(1) };
    cal.validate(p).map_err(|e| {
        FeError::Parse(format!(
            "calibration out of range: {e}: {cal:?}; per thickness (EA, EI): {:?}",
            stacks.iter().map(|s| (s.thickness_mm, s.factors)).collect::<Vec<_>>()
        ))
    })?;
    Ok(CalibrationRun { kind, density: *d, cal, fe_hinge, stacks })
}
