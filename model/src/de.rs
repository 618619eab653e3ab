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
/// `Hold::Bonded` the stack bonded to the hinge and free across its width (pure shear),
/// `Hold::Laminate` held across too, which keeps N_L z0 (docs/materials.md "Free film and
/// bonded stack"). The solves' state of a stack is the free film's thickness; its stiffness
/// and actuation are the laminate's (`StackStiffness`).
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

/// The stack's stiffness on one sub-element, the one kernel every solve uses (docs/model.md
/// "Joint compliance with the stack", replacing the paper's Eq. 24-28), as a function of the
/// stack's state t: the thickness its free film relaxes to at the voltage (mm; the guard's
/// thickness, one to one with the voltage), and of how the stack is held (`material::Hold`,
/// docs/materials.md "Free film and bonded stack"): one law, its constraint a parameter.
///
/// The beam: a uniform beam of modulus E_de, width w, thickness t and length L parallel to the
/// hinge, its centroid offset d = (t_min + t)/2 to the extensor side, moved to the hinge
/// centreline, `Tᵀ C_de⁻¹ T` with T = [[1,0,d],[0,1,0],[0,0,1]], EA and EI scaled by the FE
/// calibration's factors g = g0 + g1 t (`Calibration`):
/// K(t) = g_a EA/L (1, 0, d)ᵀ(1, 0, d) + g_b E w t³ [[0,0,0],[0,1/L³,-1/(2L²)],[0,-1/(2L²),1/(3L)]],
/// EA = E w t.
/// - `Hold::FreeFilm` (what the solves take today, `Finger::stack`): the beam at the free
///   film's thickness t, its width kept. It exerts no force at 0 load (not held along the
///   hinge, nothing to push on).
/// - `Hold::Laminate` (bonded, held across its width: `Finger::stack_held`): the stack keeps
///   N_L z0 and its section, `K = kappa(t) K(t0)` with `kappa = 1 - b/4`, `b = beta/G = s - s⁴`
///   at s = t/t0 (the tangent 4 G - beta over 4 G, `material::laminate_of_free_film`), and it
///   pushes on the hinge with the blocked stress beta ([`StackStiffness::active`]).
///
/// Its constants are taken once (`new`, `with_hold`); `upper` is K's upper triangle at t,
/// `upper_dt` its derivative in t.
#[derive(Clone, Copy, Debug)]
pub struct StackStiffness<R> {
    /// E_de w.
    ew: R,
    /// L.
    len: R,
    t_min: R,
    cal: Calibration<R>,
    /// The laminate (else the free film).
    laminate: bool,
    /// The laminate's K(t0) upper triangle.
    k0: [R; 6],
    /// 1 / (N_L z0), 1/mm (0 without stacks).
    inv_t0: R,
    /// The laminate's blocked force per unit b = beta/G on the hinge's centreline, g_a(t0) G A0
    /// (N), and its moment arm d0 = (t_min + t0)/2 (mm): the active wrench is `b (N, 0, N d0)`.
    push: [R; 2],
}

impl<R: Real> StackStiffness<R> {
    /// The free film's kernel (the solves') of parameter set `p`'s stack on a sub-element of
    /// length `len` (mm), with the calibration `cal` (`Calibration::none()`: the beam as it is).
    pub fn new(p: &Params<R>, len: R, cal: &Calibration<R>) -> Self {
        Self::build(p, len, cal, false)
    }

    /// The kernel under `hold`: `FreeFilm` (`new`) or `Laminate`. The pure-shear `Bonded`
    /// stack has no kernel (its thinning is `material::held_equilibrium_ratio`'s): refused.
    pub fn with_hold(p: &Params<R>, len: R, cal: &Calibration<R>, hold: Hold) -> Result<Self, Error> {
        match hold {
            Hold::FreeFilm => Ok(Self::build(p, len, cal, false)),
            Hold::Laminate => Ok(Self::build(p, len, cal, true)),
            Hold::Bonded => Err(Error::Input { input: "hold", reason: "the stack's kernel is the free film's or the laminate's" }),
        }
    }

    fn build(p: &Params<R>, len: R, cal: &Calibration<R>, laminate: bool) -> Self {
        let t0 = R::from_u32(p.layers) * p.z0;
        let ew = p.e_de() * p.w;
        let k0 = beam_upper(ew, len, p.t_min, cal, t0);
        let inv_t0 = if t0 > R::zero() { R::one() / t0 } else { R::zero() };
        let ga = cal.stack_axial[0] + cal.stack_axial[1] * t0;
        let g = p.e_de() / (R::from_f64(2.0) * (R::one() + p.nu));
        let push = [ga * g * p.w * t0, (p.t_min + t0) * R::from_f64(0.5)];
        StackStiffness { ew, len, t_min: p.t_min, cal: *cal, laminate, k0, inv_t0, push }
    }

    /// K's upper triangle (k00, k01, k02, k11, k12, k22) at state t, mm (k01 is zero: the
    /// stack couples no shear to the axial force).
    #[inline(always)]
    pub fn upper(&self, t: R) -> [R; 6] {
        if self.laminate {
            let (_, kappa, _) = crate::material::laminate_of_free_film(t * self.inv_t0);
            self.k0.map(|k| k * kappa)
        } else {
            beam_upper(self.ew, self.len, self.t_min, &self.cal, t)
        }
    }

    /// dK/dt's upper triangle at state t (the derivative of `upper`, term by term).
    pub fn upper_dt(&self, t: R) -> [R; 6] {
        if self.laminate {
            let (_, _, dkappa_ds) = crate::material::laminate_of_free_film(t * self.inv_t0);
            let d = dkappa_ds * self.inv_t0;
            return self.k0.map(|k| k * d);
        }
        let l = self.len;
        let (l2, half) = (l * l, R::from_f64(0.5));
        let l3 = l2 * l;
        let (ga0, gb0) = (self.cal.stack_axial, self.cal.stack_bending);
        let ga = ga0[0] + ga0[1] * t;
        let gb = gb0[0] + gb0[1] * t;
        // the axial part g_a EA/L (1, 0, d)ᵀ(1, 0, d), EA/L = ew t / L
        let ka = self.ew / l;
        let gka = ga * ka * t;
        let dgka = ga0[1] * ka * t + ga * ka;
        let d = (self.t_min + t) * half;
        let dk02 = dgka * d + gka * half;
        // the bending part g_b E w t³ (1/L³, -1/(2L²), 1/(3L))
        let t2 = t * t;
        let de3 = self.ew * (gb0[1] * t2 * t + gb * R::from_f64(3.0) * t2);
        [dgka, R::zero(), dk02, de3 / l3, -de3 * half / l2, de3 / (R::from_f64(3.0) * l) + dk02 * d + gka * d * half]
    }

    /// K at state t, mm.
    pub fn matrix(&self, t: R) -> Mat3<R> {
        mat3::from_upper(self.upper(t))
    }

    /// The stack's active wrench on one sub-element at state t (N, N, N·mm; the sub-element's
    /// frame): the laminate's blocked stress beta over its calibrated section,
    /// `b g_a G A0 (1, 0, d0)`, internal to the sub-element (the stack pushes its two ends apart
    /// along its centroid line, d0 to the extensor side, which turns the joint toward the
    /// cable: a unimorph). Zero at 0 V, and for the free film (nothing holds it along the hinge).
    pub fn active(&self, t: R) -> [R; 3] {
        if !self.laminate {
            return [R::zero(); 3];
        }
        let (b, _, _) = crate::material::laminate_of_free_film(t * self.inv_t0);
        let n = b * self.push[0];
        [n, R::zero(), n * self.push[1]]
    }
}

/// The calibrated beam's upper triangle at thickness t (`StackStiffness`'s K0 at t = t0): the
/// beam's `C_de⁻¹` = [[EA/L, 0, 0], [0, 12EI/L³, -6EI/L²], [0, -6EI/L², 4EI/L]] moved by T,
/// then g_b K + (g_a - g_b) EA/L (1, 0, d)ᵀ(1, 0, d).
fn beam_upper<R: Real>(ew: R, len: R, t_min: R, cal: &Calibration<R>, t: R) -> [R; 6] {
    let (l, l2) = (len, len * len);
    let l3 = l2 * len;
    let ea = ew * t;
    let ei = ea * t * t / R::from_f64(12.0);
    let ka = ea / l;
    let (k11, k12, k22) = (R::from_f64(12.0) * ei / l3, R::from_f64(-6.0) * ei / l2, R::from_f64(4.0) * ei / l);
    let d = (t_min + t) / R::from_f64(2.0);
    // Tᵀ K T, T = I + d e0 e2ᵀ
    let k02 = ka * d;
    let k22 = k22 + k02 * d;
    // the calibration: g_b K + (g_a - g_b) K_a
    let ga = cal.stack_axial[0] + cal.stack_axial[1] * t;
    let gb = cal.stack_bending[0] + cal.stack_bending[1] * t;
    let ga_ka = (ga - gb) * ka;
    [gb * ka + ga_ka, R::zero(), gb * k02 + ga_ka * d, gb * k11, gb * k12, gb * k22 + ga_ka * d * d]
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

    /// The laminate's kernel: the beam at N_L z0 times `kappa = 1 - b/4` at the state (the free
    /// film's thickness), `upper_dt` its derivative (central differences), its active wrench
    /// `b g_a G A0 (1, 0, d0)`, zero at 0 V; the free film's kernel pushes nothing and is the
    /// beam at t (the solves unchanged); the pure-shear layer has no kernel.
    #[test]
    fn the_laminate_kernel_keeps_its_section_softens_by_kappa_and_pushes() {
        for cal in [Calibration::<f64>::none(), Calibration::model_md()] {
            let p = Params::<f64>::vhb4905();
            let len = p.hinge_len() / p.m as f64;
            let lam = StackStiffness::with_hold(&p, len, &cal, Hold::Laminate).unwrap();
            let free = StackStiffness::with_hold(&p, len, &cal, Hold::FreeFilm).unwrap();
            let t0 = f64::from(p.layers) * p.z0;
            let k0 = free.upper(t0);
            assert_eq!(lam.upper(t0), k0, "at 0 V the two are one beam");
            let g = p.stack_law().unwrap().g_eq;
            let ga = cal.stack_axial[0] + cal.stack_axial[1] * t0;
            let top = voltage_ceiling(&p);
            for i in 0..=10 {
                let v = 0.999 * top * f64::from(i) / 10.0;
                let t = stack_thickness(&p, 1, v).unwrap();
                let s = t / t0;
                let b = s - s.powi(4);
                let got = lam.upper(t);
                for e in 0..6 {
                    assert!((got[e] - (1.0 - b / 4.0) * k0[e]).abs() <= 1e-12 * k0[e].abs().max(1e-9), "entry {e} at {v} V");
                }
                let h = 1e-6 * t;
                let (up, dn, dt) = (lam.upper(t + h), lam.upper(t - h), lam.upper_dt(t));
                for e in 0..6 {
                    assert!((dt[e] - (up[e] - dn[e]) / (2.0 * h)).abs() <= 1e-6 * k0[e].abs().max(1e-9) / t, "entry {e}");
                }
                let w = lam.active(t);
                let n = b * ga * g * p.w * t0;
                assert!((w[0] - n).abs() <= 1e-12 * n.max(1e-12) && w[1] == 0.0 && (w[2] - n * (p.t_min + t0) / 2.0).abs() <= 1e-12 * n.max(1e-12));
                assert!(if i == 0 { w[0] == 0.0 } else { w[0] > 0.0 });
                assert_eq!(free.active(t), [0.0; 3]);
                assert_eq!(free.upper(t), StackStiffness::new(&p, len, &cal).upper(t));
            }
            assert!(StackStiffness::with_hold(&p, len, &cal, Hold::Bonded).is_err());
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
        for h in [Hold::FreeFilm, Hold::Bonded, Hold::Laminate] {
            assert!(matches!(stack_thickness_held(&p, 1, top * 1.001, h), Err(Error::VoltageCeiling { .. })), "{h:?}");
        }
        // the laminate keeps its thickness
        assert_eq!(stack_thickness_held(&p, 1, 0.999 * top, Hold::Laminate).unwrap(), stack_thickness(&p, 1, 0.0).unwrap());
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
