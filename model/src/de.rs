//! The dielectric-elastomer stack in the finger model: each layer's thickness at a voltage
//! held long enough (the film's law at equilibrium, `material`), the voltage ceiling, and the
//! stack's stiffness as a uniform beam parallel to the hinge.
//!
//! The thinning is the finite-strain free film of the parameter set's card (docs/materials.md):
//! `G (s - s^4) = eps0 eps_r V^2 / z0^2` relaxed, G = E_de / (2 (1 + nu)); its stable branch ends
//! at s = 4^(-1/3) (pull-in) and passes the 33 % limit s = 2/3 before that, so the ceiling is
//! margin x min(the voltage that holds s = 2/3, the breakdown field there), capped by the supply.
//! The paper's Eq. 1-2 (Maxwell pressure on z0, linear) and the linear law on the current
//! thickness are not used; docs/materials.md compares them.
//!
//! What it is not: the law in time (`material`: the firmware's per-tick state), the joint
//! assembly (`finger`).

use crate::calibration::Calibration;
use crate::error::Error;
use crate::mat3::{self, Mat3};
use crate::material::{self, Hold, StackLaw, LIMIT_RATIO};
use crate::params::Params;
use crate::real::Real;

/// The parameter set's film law, or the error that names the parameter that breaks it.
fn law<R: Real>(p: &Params<R>) -> Result<StackLaw<R>, Error> {
    p.stack_law()
}

/// Equilibrium pull-in voltage of one layer, V: where the stable branch of the relaxed film
/// balance ends (s = 4^(-1/3)). Zero without stacks or with an invalid film.
pub fn pull_in_voltage<R: Real>(p: &Params<R>) -> R {
    if p.layers == 0 {
        return R::zero();
    }
    law(p).map(|l| material::equilibrium_pull_in_voltage(&l)).unwrap_or(R::zero())
}

/// The ceiling no channel may reach: min(hold ceiling, supply maximum), V, the hold ceiling
/// `margin min(V_eq(2/3), E_B(2/3) 2/3 z0)` of the set's film (`material::hold_ceiling`).
/// Zero without stacks or with an invalid film.
pub fn voltage_ceiling<R: Real>(p: &Params<R>) -> R {
    Stack::new(p).ceiling()
}

/// The ceiling in force on a channel, V: `min(hold ceiling, v_supply, hv_fs)` (`hv_fs` the HV
/// modules' full scale when a board drives them). The inverse, the console and the firmware
/// take their ceiling from it.
pub fn ceiling_in_force<R: Real>(p: &Params<R>, hv_fs: Option<R>) -> R {
    let v = voltage_ceiling(p);
    match hv_fs {
        Some(fs) => v.min(fs),
        None => v,
    }
}

/// Check one channel voltage: finite, not negative, and below the ceiling (0 V is always
/// allowed, also without stacks).
pub fn check_voltage<R: Real>(p: &Params<R>, joint: usize, volts: R) -> Result<(), Error> {
    check_below(joint, volts, voltage_ceiling(p))
}

/// `check_voltage` against a known ceiling.
fn check_below<R: Real>(joint: usize, volts: R, ceiling: R) -> Result<(), Error> {
    if !volts.is_finite() {
        return Err(Error::NonFinite { input: "voltage" });
    }
    if volts < R::zero() {
        return Err(Error::Input { input: "voltage", reason: "must not be negative" });
    }
    if volts > R::zero() && volts >= ceiling {
        return Err(Error::VoltageCeiling { joint, volts: volts.to_f64(), ceiling: ceiling.to_f64() });
    }
    Ok(())
}

/// Thickness ratio s = z/z0 of one layer held at `volts` until relaxed
/// (`material::equilibrium_ratio`, the stable branch). Errors past pull-in.
pub fn layer_thickness_ratio<R: Real>(p: &Params<R>, joint: usize, volts: R) -> Result<R, Error> {
    ratio(&law(p)?, joint, volts)
}

fn ratio<R: Real>(l: &StackLaw<R>, joint: usize, volts: R) -> Result<R, Error> {
    material::equilibrium_ratio(l, volts).map_err(|e| match e {
        Error::PullIn { volts, pull_in } => Error::VoltageCeiling { joint, volts, ceiling: pull_in },
        e => e,
    })
}

/// Whole-stack thickness t_k = N_L z(V_k), mm, after checking the voltage against the ceiling.
pub fn stack_thickness<R: Real>(p: &Params<R>, joint: usize, volts: R) -> Result<R, Error> {
    Stack::new(p).thickness(joint, volts)
}

/// The stack's thickness t_k = N_L z(V_k) under `hold`, mm, after checking the voltage against
/// the ceiling (the free film's, whatever the hold): `Hold::FreeFilm` is `stack_thickness`;
/// `Hold::Bonded` is the stack as bonded to the hinge (docs/materials.md "Free film and bonded
/// stack"), the law for the stiffness a voltage buys. Not yet what the solves use: they take
/// the free film's thickness at the original width.
pub fn stack_thickness_held<R: Real>(p: &Params<R>, joint: usize, volts: R, hold: Hold) -> Result<R, Error> {
    let st = Stack::new(p);
    st.check(joint, volts)?;
    let l = st.law.as_ref().map_err(|e| *e)?;
    let s = material::held_equilibrium_ratio(l, volts, hold).map_err(|e| match e {
        Error::PullIn { volts, pull_in } => Error::VoltageCeiling { joint, volts, ceiling: pull_in },
        e => e,
    })?;
    Ok(st.t0 * s)
}

/// The voltage that thins the stack to `thickness_mm` once relaxed, V. Refuses a thickness at or
/// past the 33 % limit (the paper's "2 mm to 1 mm" is a 50 % reduction) and a voltage at or past
/// the ceiling.
pub fn voltage_for_thickness<R: Real>(p: &Params<R>, joint: usize, thickness_mm: R) -> Result<R, Error> {
    Stack::new(p).voltage(joint, thickness_mm)
}

/// A parameter set's stack, its constants computed once (the stack at 0 V, the film's law, the
/// ceiling): a solve builds one and checks, thins and inverts every joint's voltage with it.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Stack<R> {
    t0: R,
    /// The film's law, or why the set has none (also without stacks: `layers`).
    law: Result<StackLaw<R>, Error>,
    ceiling: R,
}

impl<R: Real> Stack<R> {
    /// The constants of parameter set `p`.
    pub fn new(p: &Params<R>) -> Self {
        let law = law(p);
        let ceiling = match (&law, p.layers) {
            (_, 0) | (Err(_), _) => R::zero(),
            (Ok(l), _) => material::hold_ceiling(l, l.margin).min(p.v_supply),
        };
        Stack { t0: R::from_u32(p.layers) * p.z0, law, ceiling }
    }

    /// The ceiling (`voltage_ceiling`), V.
    pub fn ceiling(&self) -> R {
        self.ceiling
    }

    /// `check_voltage`.
    pub fn check(&self, joint: usize, volts: R) -> Result<(), Error> {
        check_below(joint, volts, self.ceiling)
    }

    /// `stack_thickness`: the voltage checked, then N_L z(V), mm.
    pub fn thickness(&self, joint: usize, volts: R) -> Result<R, Error> {
        self.check(joint, volts)?;
        let l = self.law.as_ref().map_err(|e| *e)?;
        Ok(self.t0 * ratio(l, joint, volts)?)
    }

    /// The voltage that thins joint `joint`'s stack to `thickness_mm`, V (`voltage_for_thickness`).
    pub fn voltage(&self, joint: usize, thickness_mm: R) -> Result<R, Error> {
        if !thickness_mm.is_finite() {
            return Err(Error::NonFinite { input: "thickness" });
        }
        let t0 = self.t0;
        let law = match &self.law {
            Ok(l) if thickness_mm <= t0 && thickness_mm > R::zero() => l,
            _ => return Err(Error::Input { input: "thickness", reason: "must lie in (0, N_L z0]" }),
        };
        let s = thickness_mm / t0;
        let limit = R::from_f64(LIMIT_RATIO);
        if s <= limit {
            return Err(Error::ThicknessLimit { joint, requested_mm: thickness_mm.to_f64(), limit_mm: (t0 * limit).to_f64() });
        }
        let v = material::equilibrium_voltage(law, s)?;
        check_below(joint, v, self.ceiling)?;
        Ok(v)
    }
}

/// The stack's stiffness on one sub-element as a function of the stack thickness t (mm), the
/// one kernel every solve uses (docs/model.md "Joint compliance with the stack", replacing
/// the paper's Eq. 24-28): a uniform beam of modulus E_de, width w and length L parallel to
/// the hinge, its centroid offset d = (t_min + t)/2 to the extensor side, moved to the hinge
/// centreline, `Tᵀ C_de⁻¹ T` with T = [[1,0,d],[0,1,0],[0,0,1]], EA and EI scaled by the FE
/// calibration's factors g = g0 + g1 t (`Calibration`):
/// K = g_a EA/L (1, 0, d)ᵀ(1, 0, d) + g_b E w t³ [[0,0,0],[0,1/L³,-1/(2L²)],[0,-1/(2L²),1/(3L)]],
/// EA = E w t. Its constants are taken once (`new`); `upper` is K's upper triangle at t,
/// `upper_dt` its derivative in t.
#[derive(Clone, Copy, Debug)]
pub struct StackStiffness<R> {
    /// E_de w.
    ew: R,
    /// L, L², L³.
    len: [R; 3],
    t_min: R,
    /// The axial and bending factors' (g0, g1).
    ga: [R; 2],
    gb: [R; 2],
}

impl<R: Real> StackStiffness<R> {
    /// The constants of parameter set `p`'s stack on a sub-element of length `len` (mm), with
    /// the calibration `cal` (`Calibration::none()`: the beam as it is).
    pub fn new(p: &Params<R>, len: R, cal: &Calibration<R>) -> Self {
        let l2 = len * len;
        StackStiffness { ew: p.e_de() * p.w, len: [len, l2, l2 * len], t_min: p.t_min, ga: cal.stack_axial, gb: cal.stack_bending }
    }

    /// K's upper triangle (k00, k01, k02, k11, k12, k22) at thickness t, mm (k01 is zero: the
    /// stack couples no shear to the axial force): the beam's `C_de⁻¹` = [[EA/L, 0, 0],
    /// [0, 12EI/L³, -6EI/L²], [0, -6EI/L², 4EI/L]] moved by T, then g_b K + (g_a - g_b) EA/L
    /// (1, 0, d)ᵀ(1, 0, d).
    #[inline(always)]
    pub fn upper(&self, t: R) -> [R; 6] {
        let [l, l2, l3] = self.len;
        let ea = self.ew * t;
        let ei = ea * t * t / R::from_f64(12.0);
        let ka = ea / l;
        let (k11, k12, k22) = (R::from_f64(12.0) * ei / l3, R::from_f64(-6.0) * ei / l2, R::from_f64(4.0) * ei / l);
        let d = (self.t_min + t) / R::from_f64(2.0);
        // Tᵀ K T, T = I + d e0 e2ᵀ
        let k02 = ka * d;
        let k22 = k22 + k02 * d;
        // the calibration: g_b K + (g_a - g_b) K_a
        let ga = self.ga[0] + self.ga[1] * t;
        let gb = self.gb[0] + self.gb[1] * t;
        let ga_ka = (ga - gb) * ka;
        [gb * ka + ga_ka, R::zero(), gb * k02 + ga_ka * d, gb * k11, gb * k12, gb * k22 + ga_ka * d * d]
    }

    /// dK/dt's upper triangle at thickness t (the derivative of `upper`, term by term).
    pub fn upper_dt(&self, t: R) -> [R; 6] {
        let [l, l2, l3] = self.len;
        let half = R::from_f64(0.5);
        let ga = self.ga[0] + self.ga[1] * t;
        let gb = self.gb[0] + self.gb[1] * t;
        // the axial part g_a EA/L (1, 0, d)ᵀ(1, 0, d), EA/L = ew t / L
        let ka = self.ew / l;
        let gka = ga * ka * t;
        let dgka = self.ga[1] * ka * t + ga * ka;
        let d = (self.t_min + t) * half;
        let dk02 = dgka * d + gka * half;
        // the bending part g_b E w t³ (1/L³, -1/(2L²), 1/(3L))
        let t2 = t * t;
        let de3 = self.ew * (self.gb[1] * t2 * t + gb * R::from_f64(3.0) * t2);
        [dgka, R::zero(), dk02, de3 / l3, -de3 * half / l2, de3 / (R::from_f64(3.0) * l) + dk02 * d + gka * d * half]
    }

    /// K at thickness t, mm.
    pub fn matrix(&self, t: R) -> Mat3<R> {
        mat3::from_upper(self.upper(t))
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::finger::uniform_beam_compliance;

    /// `StackStiffness` is its definition, `Tᵀ C_de⁻¹ T` of the uniform beam with EA and EI
    /// scaled, to rounding, and `upper_dt` its derivative (central differences), with and
    /// without the calibration, for one sub-element of the default finger and for m = 1.
    #[test]
    fn stack_stiffness_is_the_calibrated_beam_and_upper_dt_its_derivative() {
        for cal in [Calibration::<f64>::none(), Calibration::model_md()] {
            for p in [Params::<f64>::default(), Params { m: 1, ..Params::default() }] {
                let len = p.hinge_len() / p.m as f64;
                let k = StackStiffness::new(&p, len, &cal);
                let t0 = f64::from(p.layers) * p.z0;
                for i in 0..=10 {
                    let t = t0 * (0.4 + 0.06 * f64::from(i));
                    let (ga, gb) = (cal.stack_axial[0] + cal.stack_axial[1] * t, cal.stack_bending[0] + cal.stack_bending[1] * t);
                    // the beam with EA scaled by g_a (modulus and width g_a E, w) and EI by g_b
                    let ca = uniform_beam_compliance(ga * p.e_de(), p.w, t, len);
                    let cb = uniform_beam_compliance(gb * p.e_de(), p.w, t, len);
                    let kb = mat3::inverse(&cb).unwrap();
                    let mut c_de = [[1.0 / ca[0][0], 0.0, 0.0], [0.0, kb[1][1], kb[1][2]], [0.0, kb[2][1], kb[2][2]]];
                    let d = (p.t_min + t) / 2.0;
                    // Tᵀ K T, T = I + d e0 e2ᵀ
                    for r in 0..3 {
                        c_de[r][2] += c_de[r][0] * d;
                    }
                    for c in 0..3 {
                        c_de[2][c] += c_de[0][c] * d;
                    }
                    let got = k.matrix(t);
                    let scale = c_de.iter().flatten().fold(0.0f64, |a, x| a.max(x.abs()));
                    for r in 0..3 {
                        for c in 0..3 {
                            assert!((got[r][c] - c_de[r][c]).abs() <= 1e-12 * scale, "{got:?} vs {c_de:?} at t = {t}");
                        }
                    }
                    let h = 1e-6 * t;
                    let (up, dn, dt) = (k.upper(t + h), k.upper(t - h), k.upper_dt(t));
                    for e in 0..6 {
                        let fd = (up[e] - dn[e]) / (2.0 * h);
                        assert!((dt[e] - fd).abs() <= 1e-7 * scale / t, "entry {e}: {} vs {fd} at t = {t}", dt[e]);
                    }
                }
            }
        }
    }

    /// The held thickness: the free film's is `stack_thickness` exactly; the bonded stack is
    /// thicker at every voltage in (0, ceiling), the same at 0 V; a voltage past the ceiling is
    /// refused for both holds (the ceiling stays the free film's).
    #[test]
    fn stack_thickness_held_is_the_free_film_or_the_thicker_bonded_stack_under_one_ceiling() {
        let p = Params::<f64>::vhb4905();
        let top = voltage_ceiling(&p);
        for i in 0..=10 {
            let v = 0.999 * top * f64::from(i) / 10.0;
            let free = stack_thickness_held(&p, 1, v, Hold::FreeFilm).unwrap();
            assert_eq!(free.to_bits(), stack_thickness(&p, 1, v).unwrap().to_bits());
            let bonded = stack_thickness_held(&p, 1, v, Hold::Bonded).unwrap();
            assert!(if i == 0 { bonded == free } else { bonded > free }, "{v}: {bonded} vs {free}");
        }
        for h in [Hold::FreeFilm, Hold::Bonded] {
            assert!(matches!(stack_thickness_held(&p, 1, top * 1.001, h), Err(Error::VoltageCeiling { .. })), "{h:?}");
        }
    }

    /// A thickness outside (0, N_L z0] is refused as an input, not as the thinning limit: the
    /// stack neither thickens under a voltage nor thins to nothing.
    #[test]
    fn voltage_for_thickness_refuses_a_thickness_outside_the_stack() {
        let p = Params::<f64>::default();
        let t0 = f64::from(p.layers) * p.z0;
        for t in [0.0, -0.1, 1.5 * t0] {
            assert!(matches!(voltage_for_thickness(&p, 1, t), Err(Error::Input { input: "thickness", .. })), "{t}");
        }
        assert!(matches!(voltage_for_thickness(&p, 1, 0.5 * t0), Err(Error::ThicknessLimit { .. })));
    }
}
