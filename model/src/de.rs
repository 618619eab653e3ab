//! The dielectric-elastomer stack (MODEL.md "Dielectric elastomer stack", paper section II-A
//! corrected): layer thinning under the Maxwell pressure on the current thickness, the
//! pull-in (33 %) limit, the voltage ceiling, and the stack's stiffness as a uniform beam
//! parallel to the hinge.
//!
//! Corrections to the paper, in short (docs/model.md has the reasons):
//! - Eq. 1-2 put the initial thickness z0 in the Maxwell pressure. With the current thickness z
//!   the balance `E (1 - z/z0) = eps0 eps_r V^2 / z^2` has a stable branch only down to
//!   z = 2/3 z0, which is the 33 % limit the paper quotes; with z0 the limit would be passed by
//!   a factor 1.5 in voltage without any warning.
//! - Eq. 3 inverts the isotropic relation; `Params::e_de` uses E = 2 G (1 + nu) unless the
//!   paper preset is selected.
//!
//! What it is not: the joint assembly (see `joint`).

use crate::error::Error;
use crate::mat3::Mat3;
use crate::params::{Params, EPS0};
use crate::real::Real;
use crate::solve::newton::{self, Equations};
use crate::solve::SolveOptions;

/// `eps0 * eps_r` in the model's units: the Maxwell pressure in MPa is this times V^2/z[mm]^2.
fn permittivity<R: Real>(p: &Params<R>) -> R {
    R::from_f64(EPS0) * p.eps_r
}

/// Pull-in voltage of one layer, V: `V_pi = sqrt(4 E_de z0^2 / (27 eps0 eps_r))`, where the
/// stable branch of the thinning balance ends, at z = 2/3 z0 (s^2 (1 - s) peaks at s = 2/3 with
/// value 4/27).
pub fn pull_in_voltage<R: Real>(p: &Params<R>) -> R {
    if p.layers == 0 {
        return R::zero();
    }
    (R::from_f64(4.0) * p.e_de() * p.z0 * p.z0 / (R::from_f64(27.0) * permittivity(p))).sqrt()
}

/// The ceiling no channel may reach: min(margin x V_pi, supply maximum), V. Zero without stacks.
pub fn voltage_ceiling<R: Real>(p: &Params<R>) -> R {
    (p.margin * pull_in_voltage(p)).min(p.v_supply)
}

/// The ceiling in force on a channel, V: `min(margin x V_pi, v_supply, hv_fs)` (MODEL.md
/// "Dielectric elastomer stack", the 33 % pull-in limit with margin; `hv_fs` the HV modules'
/// full scale when a board drives them). The inverse, the console and the firmware take their
/// ceiling from it.
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

/// Thickness ratio s = z/z0 of one layer at `volts`: the root of
/// `s^2 (1 - s) = beta`, `beta = eps0 eps_r V^2 / (E_de z0^2)`, on the stable branch
/// s in [2/3, 1] (the corrected Eq. 1-2). Newton (`solve::newton`) from s = 1: the cubic is concave and
/// decreasing there, so the iterates fall monotonically onto the root and never cross it.
/// Errors past pull-in (beta >= 4/27).
pub fn layer_thickness_ratio<R: Real>(p: &Params<R>, joint: usize, volts: R) -> Result<R, Error> {
    let beta = permittivity(p) * volts * volts / (p.e_de() * p.z0 * p.z0);
    if !beta.is_finite() || beta >= R::from_f64(4.0 / 27.0) {
        return Err(Error::VoltageCeiling {
            joint,
            volts: volts.to_f64(),
            ceiling: pull_in_voltage(p).to_f64(),
        });
    }
    let mut s = [R::one()];
    let tol = R::from_f64(4.0 * R::EPS);
    let opts = SolveOptions::new(tol, R::from_f64(16.0 * R::EPS), 60);
    if newton::solve(&mut Thinning { beta }, &mut s, &opts).is_err() {
        return Err(Error::NotConverged { iterations: 60, residual: f64::INFINITY });
    }
    let s = s[0];
    Ok(s.max(R::from_f64(2.0 / 3.0)))
}

/// The layer's thinning residual s^2 (1 - s) - beta and its slope, for `solve::newton`.
struct Thinning<R> {
    beta: R,
}

impl<R: Real> Equations<R, 1> for Thinning<R> {
    type Refusal = ();
    fn residual(&mut self, s: &[R; 1], _: usize) -> Result<[R; 1], ()> {
        Ok([s[0] * s[0] * (R::one() - s[0]) - self.beta])
    }
    fn jacobian(&mut self, s: &[R; 1], _: &[R; 1], _: usize) -> Result<[[R; 1]; 1], ()> {
        Ok([[s[0] * (R::from_f64(2.0) - R::from_f64(3.0) * s[0])]])
    }
}

/// Whole-stack thickness t_k = N_L z(V_k), mm, after checking the voltage against the ceiling.
pub fn stack_thickness<R: Real>(p: &Params<R>, joint: usize, volts: R) -> Result<R, Error> {
    check_voltage(p, joint, volts)?;
    let s = layer_thickness_ratio(p, joint, volts)?;
    Ok(R::from_u32(p.layers as u32) * p.z0 * s)
}

/// The voltage that thins the stack to `thickness_mm`, V. Refuses a thickness at or past the
/// 33 % limit (the paper's "2 mm to 1 mm" is a 50 % reduction) and a voltage at or past the
/// ceiling.
pub fn voltage_for_thickness<R: Real>(p: &Params<R>, joint: usize, thickness_mm: R) -> Result<R, Error> {
    ThicknessVoltage::new(p).voltage(joint, thickness_mm)
}

/// `voltage_for_thickness` with its parameter-set constants (stack thickness at 0 V, modulus,
/// permittivity, ceiling) computed once: the branch table keeps one for its finger.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThicknessVoltage<R> {
    has_stacks: bool,
    t0: R,
    z0: R,
    e_de: R,
    permittivity: R,
    ceiling: R,
}

impl<R: Real> ThicknessVoltage<R> {
    /// The constants of parameter set `p`.
    pub fn new(p: &Params<R>) -> Self {
        ThicknessVoltage {
            has_stacks: p.layers != 0,
            t0: R::from_u32(p.layers as u32) * p.z0,
            z0: p.z0,
            e_de: p.e_de(),
            permittivity: permittivity(p),
            ceiling: voltage_ceiling(p),
        }
    }

    /// The voltage that thins joint `joint`'s stack to `thickness_mm`, V (`voltage_for_thickness`).
    pub fn voltage(&self, joint: usize, thickness_mm: R) -> Result<R, Error> {
        if !thickness_mm.is_finite() {
            return Err(Error::NonFinite { input: "thickness" });
        }
        let t0 = self.t0;
        if !self.has_stacks || thickness_mm > t0 || thickness_mm <= R::zero() {
            return Err(Error::Input { input: "thickness", reason: "must lie in (0, N_L z0]" });
        }
        let s = thickness_mm / t0;
        let limit = R::from_f64(2.0 / 3.0);
        if s <= limit {
            return Err(Error::ThicknessLimit {
                joint,
                requested_mm: thickness_mm.to_f64(),
                limit_mm: (t0 * limit).to_f64(),
            });
        }
        let beta = s * s * (R::one() - s);
        let v = (beta * self.e_de * self.z0 * self.z0 / self.permittivity).sqrt();
        check_below(joint, v, self.ceiling)?;
        Ok(v)
    }
}

/// Stiffness of a stack stretch of length `len` and thickness `t` (mm), a uniform beam of
/// modulus E_de parallel to the hinge with its centroid offset d = t_min/2 + t/2 to the
/// extensor side, moved to the hinge centreline: `Tᵀ C_de⁻¹ T`, T = [[1,0,d],[0,1,0],[0,0,1]]
/// (MODEL.md, replacing the paper's Eq. 24-28).
/// `C_de⁻¹ = [[EA/L,0,0],[0,12EI/L³,-6EI/L²],[0,-6EI/L²,4EI/L]]`.
pub fn stack_stiffness<R: Real>(p: &Params<R>, len: R, t: R) -> Mat3<R> {
    let e = p.e_de();
    let ea = e * p.w * t;
    let ei = e * p.w * t * t * t / R::from_f64(12.0);
    let z = R::zero();
    let k: Mat3<R> = [
        [ea / len, z, z],
        [z, R::from_f64(12.0) * ei / (len * len * len), R::from_f64(-6.0) * ei / (len * len)],
        [z, R::from_f64(-6.0) * ei / (len * len), R::from_f64(4.0) * ei / len],
    ];
    let d = (p.t_min + t) / R::from_f64(2.0);
    // Tᵀ K T with T = I + d e0 e2ᵀ
    let mut o = k;
    for i in 0..3 {
        o[i][2] += k[i][0] * d;
    }
    for j in 0..3 {
        o[2][j] += o[0][j] * d;
    }
    o
}
