//! The dielectric-elastomer stack in the finger model: each layer's thickness at a voltage
//! held long enough (the film's law at equilibrium, `material`), the voltage ceiling, and the
//! stack's stiffness as a uniform beam parallel to the hinge.
//!
//! The thinning is the finite-strain free film of the parameter set's card (docs/materials.md):
//! `G (s - s^4) = eps0 eps_r V^2 / z0^2` relaxed, G = E_de / (2 (1 + nu)); its stable branch ends
//! at s = 4^(-1/3) (pull-in) and passes the 33 % limit s = 2/3 before that, so the ceiling is
//! margin x min(the voltage that holds s = 2/3, the breakdown field there), capped by the supply.
//! The paper's Eq. 1-2 (Maxwell pressure on z0, linear) and MODEL.md's linear law on the current
//! thickness are not used; docs/materials.md compares them.
//!
//! What it is not: the law in time (`material`: the firmware's per-tick state), the joint
//! assembly (`finger`).

use crate::error::Error;
use crate::mat3::Mat3;
use crate::material::{self, StackLaw, LIMIT_RATIO};
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
    if p.layers == 0 {
        return R::zero();
    }
    match law(p) {
        Ok(l) => material::hold_ceiling(&l, l.margin).min(p.v_supply),
        Err(_) => R::zero(),
    }
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
    let l = law(p)?;
    material::equilibrium_ratio(&l, volts).map_err(|e| match e {
        Error::PullIn { volts, pull_in } => Error::VoltageCeiling { joint, volts, ceiling: pull_in },
        e => e,
    })
}

/// Whole-stack thickness t_k = N_L z(V_k), mm, after checking the voltage against the ceiling.
pub fn stack_thickness<R: Real>(p: &Params<R>, joint: usize, volts: R) -> Result<R, Error> {
    check_voltage(p, joint, volts)?;
    let s = layer_thickness_ratio(p, joint, volts)?;
    Ok(R::from_u32(p.layers as u32) * p.z0 * s)
}

/// The voltage that thins the stack to `thickness_mm` once relaxed, V. Refuses a thickness at or
/// past the 33 % limit (the paper's "2 mm to 1 mm" is a 50 % reduction) and a voltage at or past
/// the ceiling.
pub fn voltage_for_thickness<R: Real>(p: &Params<R>, joint: usize, thickness_mm: R) -> Result<R, Error> {
    ThicknessVoltage::new(p).voltage(joint, thickness_mm)
}

/// `voltage_for_thickness` with its parameter-set constants (stack thickness at 0 V, the film's
/// law, ceiling) computed once: the branch table keeps one for its finger.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ThicknessVoltage<R> {
    t0: R,
    /// None without stacks or with an invalid film.
    law: Option<StackLaw<R>>,
    ceiling: R,
}

impl<R: Real> ThicknessVoltage<R> {
    /// The constants of parameter set `p`.
    pub fn new(p: &Params<R>) -> Self {
        ThicknessVoltage {
            t0: R::from_u32(p.layers as u32) * p.z0,
            law: if p.layers != 0 { law(p).ok() } else { None },
            ceiling: voltage_ceiling(p),
        }
    }

    /// The voltage that thins joint `joint`'s stack to `thickness_mm`, V (`voltage_for_thickness`).
    pub fn voltage(&self, joint: usize, thickness_mm: R) -> Result<R, Error> {
        if !thickness_mm.is_finite() {
            return Err(Error::NonFinite { input: "thickness" });
        }
        let t0 = self.t0;
        let law = match &self.law {
            Some(l) if thickness_mm <= t0 && thickness_mm > R::zero() => l,
            _ => return Err(Error::Input { input: "thickness", reason: "must lie in (0, N_L z0]" }),
        };
        let s = thickness_mm / t0;
        let limit = R::from_f64(LIMIT_RATIO);
        if s <= limit {
            return Err(Error::ThicknessLimit {
                joint,
                requested_mm: thickness_mm.to_f64(),
                limit_mm: (t0 * limit).to_f64(),
            });
        }
        let v = material::equilibrium_voltage(law, s)?;
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
