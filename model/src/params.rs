//! The finger's parameters (docs/model.md "Geometry", "Dielectric elastomer stack", "Cable"),
//! their defaults, the paper preset, validation, and access by name for the console.
//!
//! What it is not: derived quantities (compliances, pull-in) live in `hinge`, `de`, `finger`.

use crate::error::Error;
use crate::material::{Card, StackLaw, PAPER_ELASTIC, VHB_4905};
use crate::real::Real;

/// Most joints a finger may have (fixed capacity; the paper's finger has 3).
pub const MAX_JOINTS: usize = 5;
/// Most sub-elements per hinge (m; m = 1 is the paper's model).
pub const MAX_SUB: usize = 8;
/// Most DE layers per stack.
pub const MAX_LAYERS: u32 = 64;

pub use crate::material::EPS0;

/// Standard gravity, m/s² (the board's finger's `grav`).
pub const G_STANDARD: f64 = 9.81;
/// The body's density, g/cm³: a TPU of Shore 85A, NinjaTek NinjaFlex technical data sheet
/// (specific gravity 1.19, ASTM D792).
pub const RHO_TPU_G_CM3: f64 = 1.19;

/// How the stack's Young's modulus follows from G and nu.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum DeModulusRule {
    /// Isotropic elasticity: E = 2 G (1 + nu) (docs/model.md's correction).
    Isotropic,
    /// The paper's Eq. 3 as printed: E = G / (2 (1 + nu)). Only for reproducing its scenes.
    PaperEq3,
}

/// Every model parameter. Units: mm, N, MPa, V (docs/model.md "Units and frames").
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Params<R> {
    /// Number of elements (joints), 1..=MAX_JOINTS.
    pub n: usize,
    /// Element pitch, node to node, mm.
    pub l: R,
    /// Link thickness in the bending plane, mm.
    pub b: R,
    /// Width out of the plane (the paper's h), mm.
    pub w: R,
    /// Thinnest hinge section, mm.
    pub t_min: R,
    /// Elliptical notch semi-axis along x, mm; hinge length L_h = 2a.
    pub a: R,
    /// Body Young's modulus, MPa.
    pub e_b: R,
    /// Cable offset from the centerline on the flexor side, mm.
    pub e: R,
    /// DE layers per stack (0: no stacks).
    pub layers: u32,
    /// Initial thickness of one DE layer, mm.
    pub z0: R,
    /// DE shear modulus, MPa.
    pub g: R,
    /// DE Poisson ratio.
    pub nu: R,
    /// DE relative permittivity.
    pub eps_r: R,
    /// Which relation gives E_de from G and nu.
    pub de_rule: DeModulusRule,
    /// Fraction of the pull-in voltage the ceiling allows, (0, 1).
    pub margin: R,
    /// HV supply maximum, V.
    pub v_supply: R,
    /// Load increments of the paper's stepping solver.
    pub n_inc: u32,
    /// Sub-elements per hinge (m = 1 is the paper's model).
    pub m: usize,
    /// Use the plate (plane-strain) modulus E_b / (1 - nu_b^2) for the hinges.
    pub plate: bool,
    /// Body Poisson ratio (for the plate modulus).
    pub nu_b: R,
    /// Shortest cable span before the links are taken to touch (contact), mm.
    pub span_floor: R,
    /// Treat the links as beams of the body material (compression + bending under the cable's
    /// eccentric load) instead of rigid (the paper's model).
    pub flex_links: bool,
    /// The film's material card: its branches and breakdown field (its equilibrium modulus and
    /// permittivity are `g`/`nu`/`de_rule` and `eps_r` here).
    pub card: &'static Card,
    /// Gravity's magnitude, m/s² (0: off; docs/model.md "Gravity").
    pub grav: R,
    /// Gravity's direction in the base frame, degrees from the straight finger's axis (+x)
    /// toward the cable side (+y): 0 hanging straight down, 90 held horizontally curling
    /// downward, -90 curling upward, 180 pointing up. Kept in the console's unit (degrees).
    pub grav_dir: R,
    /// The body's density, g/cm³ (TPU; docs/model.md "Gravity").
    pub rho_b: R,
}

impl<R: Real> Default for Params<R> {
    /// The defaults of docs/model.md.
    fn default() -> Self {
        let f = R::from_f64;
        Params {
            n: 3,
            l: f(27.0),
            b: f(10.0),
            w: f(20.0),
            t_min: f(1.5),
            a: f(5.0),
            e_b: f(12.0),
            e: f(5.0),
            layers: 4,
            z0: f(0.5),
            g: f(0.6),
            nu: f(0.49),
            eps_r: f(4.7),
            de_rule: DeModulusRule::Isotropic,
            margin: f(0.9),
            v_supply: f(10_000.0),
            n_inc: 20,
            // The real structure (docs/fidelity.md): 8 sub-elements per hinge, the plate
            // modulus (w/t_min = 13.3 >= 10) and flexible links put the joint angles within 3 %
            // of the continuum reference up to 2 N; the paper's model (m = 1, E_b, rigid links)
            // is 32 % off there. `paper()` keeps the paper's model.
            m: 8,
            plate: true,
            nu_b: f(0.45),
            span_floor: f(0.1),
            flex_links: true,
            card: &PAPER_ELASTIC,
            // the model's default finger and the paper have no gravity; the board's finger has it
            // (`with_card`)
            grav: f(0.0),
            grav_dir: f(0.0),
            rho_b: f(RHO_TPU_G_CM3),
        }
    }
}

/// A parameter's name and its valid range, as the console reports them.
#[derive(Clone, Copy, Debug)]
pub struct ParamInfo {
    pub name: &'static str,
    pub min: f64,
    pub max: f64,
    /// Whether the bounds are exclusive.
    pub open: bool,
    pub range: &'static str,
    pub read_only: bool,
}

impl ParamInfo {
    /// Whether `v` lies in the range. Closed bounds allow a relative 1e-6 of slack, so a
    /// bound itself survives the round trip through f32 (1e-6 as f32 is 9.99999e-7).
    pub fn contains(&self, v: f64) -> bool {
        let slack = |b: f64| 1e-6 * b.abs();
        if self.open {
            v > self.min && v < self.max
        } else {
            v >= self.min - slack(self.min) && v <= self.max + slack(self.max)
        }
    }

    /// [`ParamInfo::contains`] computed in `R` (the same for f64; in f32 no f64 arithmetic
    /// is linked, which the firmware's flash budget needs).
    pub fn contains_in<R: Real>(&self, v: R) -> bool {
        let (min, max) = (R::from_f64(self.min), R::from_f64(self.max));
        let slack = |b: R| R::from_f64(1e-6) * b.abs();
        if self.open {
            v > min && v < max
        } else {
            v >= min - slack(min) && v <= max + slack(max)
        }
    }
}

/// `v` as an integer in 0..2^31 when it is one (from its bits: no f64 arithmetic).
fn small_uint(v: f64) -> Option<u32> {
    let bits = v.to_bits();
    if bits << 1 == 0 {
        return Some(0); // +-0
    }
    if bits >> 63 != 0 {
        return None;
    }
    let e = ((bits >> 52) & 0x7ff) as i32 - 1023;
    if !(0..31).contains(&e) {
        return None;
    }
    let m = (bits & ((1u64 << 52) - 1)) | (1u64 << 52);
    let shift = 52 - e as u32;
    if m & ((1u64 << shift) - 1) != 0 {
        return None;
    }
    Some((m >> shift) as u32)
}

const fn info(name: &'static str, min: f64, max: f64, open: bool, range: &'static str) -> ParamInfo {
    ParamInfo { name, min, max, open, range, read_only: false }
}

/// The parameter table (`PARAMS`), the gravity feature's three after the rest.
macro_rules! params_table {
    ($($extra:expr),*) => {
        &[
    info("n", 1.0, MAX_JOINTS as f64, false, "integer 1..5"),
    info("l", 1e-3, 1e4, false, "1e-3..1e4 mm, > 2a"),
    info("b", 1e-3, 1e4, false, "1e-3..1e4 mm, > t_min"),
    info("w", 1e-3, 1e4, false, "1e-3..1e4 mm"),
    info("t_min", 1e-3, 1e4, false, "1e-3..1e4 mm, < b"),
    info("a", 1e-3, 1e4, false, "1e-3..1e4 mm, 2a < l"),
    info("e_b", 1e-3, 1e6, false, "1e-3..1e6 MPa"),
    info("e", 1e-3, 1e4, false, "1e-3 mm..b/2"),
    info("layers", 0.0, MAX_LAYERS as f64, false, "integer 0..64"),
    info("z0", 1e-3, 1e2, false, "1e-3..100 mm"),
    info("g", 1e-3, 1e4, false, "1e-3..1e4 MPa"),
    info("nu", 0.0, 0.5, false, "0..0.5"),
    info("eps_r", 1.0, 1e3, false, "1..1000"),
    ParamInfo { name: "e_de", min: 0.0, max: 0.0, open: false, range: "read-only", read_only: true },
    info("margin", 0.0, 1.0, true, "0 < margin < 1"),
    info("v_supply", 0.0, 1e5, false, "0..1e5 V"),
    info("n_inc", 1.0, 100_000.0, false, "integer 1..100000"),
    info("m", 1.0, MAX_SUB as f64, false, "integer 1..8"),
    info("plate", 0.0, 1.0, false, "0 or 1"),
    info("nu_b", 0.0, 0.499, false, "0..0.499"),
    info("span_floor", 1e-6, 1e3, false, "1e-6 mm..L_h"),
    info("flex_links", 0.0, 1.0, false, "0 or 1"),
            $($extra),*
        ]
    };
}

/// Every parameter by its console name, with its range. Lengths are bounded to 1e-3..1e4 mm
/// and moduli to 1e-3..1e6 MPa so that no product in the model overflows f32.
#[cfg(feature = "gravity")]
pub const PARAMS: &[ParamInfo] = params_table!(
    info("grav", 0.0, 20.0, false, "0..20 m/s2 (0: off)"),
    info("grav_dir", -180.0, 180.0, false, "-180..180 deg from +x toward +y"),
    info("rho_b", 0.0, 25.0, false, "0..25 g/cm3")
);
/// Every parameter by its console name (without the gravity feature: none of gravity's).
#[cfg(not(feature = "gravity"))]
pub const PARAMS: &[ParamInfo] = params_table!();

fn is_integer_name(name: &str) -> bool {
    matches!(name, "n" | "layers" | "n_inc" | "m" | "plate" | "flex_links")
}

impl<R: Real> Params<R> {
    /// The paper's preset: the geometry of docs/model.md with the DE modulus of Eq. 3 as printed
    /// (E = G / (2 (1 + nu)) = 0.201 MPa) and the paper's own model (one element per hinge,
    /// E_b, rigid links), to reproduce the paper's scenes.
    pub fn paper() -> Self {
        Params { de_rule: DeModulusRule::PaperEq3, ..Self::paper_model() }
    }

    /// The defaults of docs/model.md in the paper's model: one compliance per hinge (m = 1), the
    /// body modulus E_b and rigid links (the corrected DE modulus kept).
    pub fn paper_model() -> Self {
        Params { m: 1, plate: false, flex_links: false, ..Self::default() }
    }

    /// The default finger (docs/model.md) with the film of `card`: its equilibrium modulus (`g`,
    /// isotropic rule), permittivity, branches and breakdown field.
    pub fn with_card(card: &'static Card) -> Self {
        Params { g: R::from_f64(card.g_eq_mpa), eps_r: R::from_f64(card.eps_r), de_rule: DeModulusRule::Isotropic, card, ..Self::default() }
    }

    /// These parameters under gravity: `grav` m/s² along `grav_dir` degrees (docs/model.md
    /// "Gravity").
    pub fn with_gravity(self, grav: R, grav_dir: R) -> Self {
        Params { grav, grav_dir, ..self }
    }

    /// Whether gravity acts (a magnitude and a mass).
    pub fn has_gravity(&self) -> bool {
        cfg!(feature = "gravity") && self.grav > R::zero() && (self.rho_b > R::zero() || (self.layers > 0 && self.card.rho_g_cm3 > 0.0))
    }

    /// The default finger (docs/model.md) with the board's film, VHB 4905.
    pub fn vhb4905() -> Self {
        Self::with_card(&VHB_4905)
    }

    /// The film's law for one layer: the card's branches and breakdown with this set's
    /// equilibrium shear modulus `E_de / (2 (1 + nu))` (= g by the isotropic rule), eps_r, z0
    /// and margin.
    pub fn stack_law(&self) -> Result<StackLaw<R>, Error> {
        let g_eq = self.e_de() / (R::from_f64(2.0) * (R::one() + self.nu));
        StackLaw::with_film(self.card, g_eq, self.eps_r, self.z0, self.margin)
    }

    /// A finger without DE stacks.
    pub fn without_stacks(self) -> Self {
        Params { layers: 0, ..self }
    }

    /// Hinge length L_h = 2a, mm.
    pub fn hinge_len(&self) -> R {
        self.a + self.a
    }

    /// The DE Young's modulus E_de, MPa, by the selected rule.
    pub fn e_de(&self) -> R {
        let two = R::from_f64(2.0);
        match self.de_rule {
            DeModulusRule::Isotropic => two * self.g * (R::one() + self.nu),
            DeModulusRule::PaperEq3 => self.g / (two * (R::one() + self.nu)),
        }
    }

    /// The body modulus the hinges bend with: E_b, or the plate modulus E_b / (1 - nu_b^2).
    pub fn hinge_modulus(&self) -> R {
        if self.plate {
            self.e_b / (R::one() - self.nu_b.sq())
        } else {
            self.e_b
        }
    }

    /// Read a parameter by its console name.
    pub fn get(&self, name: &str) -> Option<f64> {
        Some(match name {
            "n" => self.n as f64,
            "l" => self.l.to_f64(),
            "b" => self.b.to_f64(),
            "w" => self.w.to_f64(),
            "t_min" => self.t_min.to_f64(),
            "a" => self.a.to_f64(),
            "e_b" => self.e_b.to_f64(),
            "e" => self.e.to_f64(),
            "layers" => self.layers as f64,
            "z0" => self.z0.to_f64(),
            "g" => self.g.to_f64(),
            "nu" => self.nu.to_f64(),
            "eps_r" => self.eps_r.to_f64(),
            "e_de" => self.e_de().to_f64(),
            "margin" => self.margin.to_f64(),
            "v_supply" => self.v_supply.to_f64(),
            "n_inc" => self.n_inc as f64,
            "m" => self.m as f64,
            "plate" => self.plate as u32 as f64,
            "nu_b" => self.nu_b.to_f64(),
            "span_floor" => self.span_floor.to_f64(),
            "flex_links" => self.flex_links as u32 as f64,
            #[cfg(feature = "gravity")]
            "grav" => self.grav.to_f64(),
            #[cfg(feature = "gravity")]
            "grav_dir" => self.grav_dir.to_f64(),
            #[cfg(feature = "gravity")]
            "rho_b" => self.rho_b.to_f64(),
            _ => return None,
        })
    }

    /// Set a parameter by its console name. The whole set is validated; on error nothing
    /// changes.
    pub fn set(&mut self, name: &str, value: f64) -> Result<(), Error> {
        self.set_many(&[(name, value)])
    }

    /// Set several parameters by their console names at once (a command line's or a keyword
    /// list's): each value is checked against its own range, then the whole set once, so the
    /// order does not matter (`a` may come before the `l` that makes it fit). On error nothing
    /// changes.
    pub fn set_many(&mut self, sets: &[(&str, f64)]) -> Result<(), Error> {
        let mut p = *self;
        for &(name, value) in sets {
            p.assign(name, value)?;
        }
        p.validate()?;
        *self = p;
        Ok(())
    }

    /// One value into its field after its own checks (name, finite, writable, range, integer);
    /// the set as a whole is not validated here.
    fn assign(&mut self, name: &str, value: f64) -> Result<(), Error> {
        let info = PARAMS.iter().find(|p| p.name == name).ok_or(Error::Input { input: "parameter", reason: "unknown parameter name" })?;
        if !value.is_finite() {
            return Err(Error::NonFinite { input: info.name });
        }
        let bad = Error::Param { name: info.name, range: info.range };
        if info.read_only {
            return Err(bad);
        }
        let r = R::from_f64(value);
        let int = small_uint(value);
        if !info.contains_in(r) || (is_integer_name(name) && int.is_none()) {
            return Err(bad);
        }
        let k = int.unwrap_or(0);
        let p = self;
        match name {
            "n" => p.n = k as usize,
            "l" => p.l = r,
            "b" => p.b = r,
            "w" => p.w = r,
            "t_min" => p.t_min = r,
            "a" => p.a = r,
            "e_b" => p.e_b = r,
            "e" => p.e = r,
            "layers" => p.layers = k,
            "z0" => p.z0 = r,
            "g" => p.g = r,
            "nu" => p.nu = r,
            "eps_r" => p.eps_r = r,
            "margin" => p.margin = r,
            "v_supply" => p.v_supply = r,
            "n_inc" => p.n_inc = k,
            "m" => p.m = k as usize,
            "plate" => p.plate = k != 0,
            "nu_b" => p.nu_b = r,
            "span_floor" => p.span_floor = r,
            "flex_links" => p.flex_links = k != 0,
            #[cfg(feature = "gravity")]
            "grav" => p.grav = r,
            #[cfg(feature = "gravity")]
            "grav_dir" => p.grav_dir = r,
            #[cfg(feature = "gravity")]
            "rho_b" => p.rho_b = r,
            _ => return Err(bad),
        }
        Ok(())
    }

    /// Check the whole parameter set: every value finite and in range, and the geometry
    /// consistent (t_min < b, 2a < l, the cable inside the link: 0 < e <= b/2, the span
    /// floor shorter than the hinge).
    pub fn validate(&self) -> Result<(), Error> {
        for info in PARAMS.iter().filter(|i| !i.read_only) {
            let v = self.get(info.name).unwrap_or(f64::NAN);
            if !v.is_finite() {
                return Err(Error::NonFinite { input: info.name });
            }
            if !info.contains_in(R::from_f64(v)) {
                return Err(Error::Param { name: info.name, range: info.range });
            }
        }
        // compared in R (no f64 arithmetic on the target)
        let two = R::from_f64(2.0);
        if self.t_min >= self.b {
            return Err(Error::Param { name: "t_min", range: "t_min < b" });
        }
        if two * self.a >= self.l {
            return Err(Error::Param { name: "a", range: "hinge length 2a < pitch l" });
        }
        if self.e > R::from_f64(0.5) * self.b {
            return Err(Error::Param { name: "e", range: "cable inside the link: 0 < e <= b/2" });
        }
        if self.span_floor >= two * self.a {
            return Err(Error::Param { name: "span_floor", range: "span_floor < hinge length 2a" });
        }
        let e_de = self.e_de();
        if self.layers > 0 && !(e_de > R::from_f64(1e-6) && e_de.is_finite()) {
            return Err(Error::Param { name: "e_de", range: "E_de > 0 (from g, nu)" });
        }
        Ok(())
    }

    /// The same parameters in another scalar type.
    pub fn cast<S: Real>(&self) -> Params<S> {
        let c = |x: R| S::from_f64(x.to_f64());
        Params {
            n: self.n,
            l: c(self.l),
            b: c(self.b),
            w: c(self.w),
            t_min: c(self.t_min),
            a: c(self.a),
            e_b: c(self.e_b),
            e: c(self.e),
            layers: self.layers,
            z0: c(self.z0),
            g: c(self.g),
            nu: c(self.nu),
            eps_r: c(self.eps_r),
            de_rule: self.de_rule,
            margin: c(self.margin),
            v_supply: c(self.v_supply),
            n_inc: self.n_inc,
            m: self.m,
            plate: self.plate,
            nu_b: c(self.nu_b),
            span_floor: c(self.span_floor),
            flex_links: self.flex_links,
            card: self.card,
            grav: c(self.grav),
            grav_dir: c(self.grav_dir),
            rho_b: c(self.rho_b),
        }
    }
}
