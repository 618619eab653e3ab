//! The stack's material law in time: one DE layer as an incompressible, equal-biaxial free film
//! with the voltage across its current thickness, a neo-Hookean equilibrium branch and up to
//! [`MAX_BRANCHES`] neo-Hookean Maxwell branches (docs/materials.md).
//!
//! s = z/z0 is the thickness stretch, a_i the squared viscous in-plane stretch of branch i (1 at
//! rest, 1/s relaxed), beta = eps V^2 / z0^2 (MPa, mm):
//! - film balance  `f(s; a) = G_eq (s - s^4) + sum G_i (s / a_i - s^4 a_i^2) = beta`, which is
//!   `P s - Q s^4` with `P = G_eq + sum G_i / a_i`, `Q = G_eq + sum G_i a_i^2`;
//!   its stable branch ends at `s_pi^3 = P / (4 Q)` (4^(-1/3) at equilibrium);
//! - branch flow   `da_i/dt = (1/s - s^2 a_i^3) / (3 tau_i)`.
//!
//! Here: the cards' types, the law in a scalar ([`StackLaw`]), the state ([`StackState`]), the
//! per-tick stepper ([`Relaxation`]), the kernels and the ceilings. Not here: the card values
//! (`cards`), the fine-step reference (`reference`), the stack as a beam (`de`).

pub mod cards;
pub mod drive;
pub mod reference;

pub use cards::{CARDS, ELASTOSIL_2030, PAPER_ELASTIC, VHB_4905};

use crate::error::Error;
use crate::real::Real;

/// Vacuum permittivity, F/m. With lengths in mm and pressures in MPa the Maxwell pressure is
/// `p[MPa] = EPS0 * eps_r * V^2 / z[mm]^2` (the 1e-6 of m^2->mm^2 and Pa->MPa cancel).
pub const EPS0: f64 = 8.854e-12;

/// Most Maxwell branches a card may have.
pub const MAX_BRANCHES: usize = 3;

/// The 33 % thickness limit as a thickness stretch.
pub const LIMIT_RATIO: f64 = 2.0 / 3.0;

/// One Maxwell branch: shear modulus, MPa, and relaxation time, s.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Branch {
    pub g_mpa: f64,
    pub tau_s: f64,
}

impl Branch {
    /// An unused slot.
    pub const NONE: Branch = Branch { g_mpa: 0.0, tau_s: 1.0 };
}

/// The dielectric breakdown field, taken flat in stretch: every source that measured it found
/// it rising as the film is stretched and thinned, so the unstretched figure is a lower bound
/// (docs/materials.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Breakdown {
    pub field0_v_per_um: f64,
}

/// A film's material card (values in `cards`, sources in docs/materials.md). Cards are told
/// apart by name.
#[derive(Clone, Copy, Debug)]
pub struct Card {
    pub name: &'static str,
    /// Equilibrium (long-time) shear modulus, MPa.
    pub g_eq_mpa: f64,
    pub branches: [Branch; MAX_BRANCHES],
    /// How many of `branches` are in use.
    pub branch_count: usize,
    pub eps_r: f64,
    pub breakdown: Breakdown,
    /// The film's density, g/cm³ (its stack's weight under gravity).
    pub rho_g_cm3: f64,
}

impl PartialEq for Card {
    fn eq(&self, other: &Card) -> bool {
        self.name == other.name
    }
}

impl Card {
    /// The branches in use.
    pub fn branches(&self) -> &[Branch] {
        &self.branches[..self.branch_count.min(MAX_BRANCHES)]
    }

    /// Instantaneous shear modulus G_eq + sum G_i, MPa.
    pub fn instantaneous_g_mpa(&self) -> f64 {
        self.g_eq_mpa + self.branches().iter().map(|b| b.g_mpa).sum::<f64>()
    }
}

/// The law of one layer in scalar R: a card with the layer's z0 and the margin. One per board
/// (or per parameter set).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StackLaw<R> {
    /// Equilibrium shear modulus, MPa.
    pub g_eq: R,
    /// Branch shear moduli, MPa (zero past `branches`).
    pub g: [R; MAX_BRANCHES],
    /// Branch relaxation times, s.
    pub tau: [R; MAX_BRANCHES],
    pub branches: usize,
    /// eps0 eps_r, F/m: the Maxwell pressure in MPa is this times V^2 / z[mm]^2.
    pub eps: R,
    /// Layer thickness at rest, mm.
    pub z0: R,
    /// Breakdown field (unstretched, a lower bound when stretched), V/mm.
    pub field0_v_per_mm: R,
    /// Fraction of a bound the ceilings allow, (0, 1].
    pub margin: R,
}

impl<R: Real> StackLaw<R> {
    /// The card's law for a layer of thickness `z0_mm`.
    pub fn new(card: &Card, z0_mm: R, margin: R) -> Result<Self, Error> {
        Self::with_film(card, R::from_f64(card.g_eq_mpa), R::from_f64(card.eps_r), z0_mm, margin)
    }

    /// The card's branches and breakdown with another equilibrium modulus and permittivity
    /// (the console's `g`, `eps_r`).
    pub fn with_film(card: &Card, g_eq_mpa: R, eps_r: R, z0_mm: R, margin: R) -> Result<Self, Error> {
        if !positive(g_eq_mpa) {
            return Err(Error::Param { name: "g", range: "> 0 MPa" });
        }
        if !positive(eps_r) {
            return Err(Error::Param { name: "eps_r", range: "> 0" });
        }
        if !positive(z0_mm) {
            return Err(Error::Param { name: "z0", range: "> 0 mm" });
        }
        if !(positive(margin) && margin <= R::one()) {
            return Err(Error::Param { name: "margin", range: "0 < margin <= 1" });
        }
        // the card checked in R, as one: no f64 arithmetic or compares on a target without a
        // double-precision FPU (`finite_sign`)
        let field0_v_per_um = R::from_f64(card.breakdown.field0_v_per_um);
        let mut law = StackLaw {
            g_eq: g_eq_mpa,
            g: [R::zero(); MAX_BRANCHES],
            tau: [R::one(); MAX_BRANCHES],
            branches: card.branch_count,
            eps: R::from_f64(EPS0) * eps_r,
            z0: z0_mm,
            field0_v_per_mm: field0_v_per_um * R::from_f64(1e3),
            margin,
        };
        let mut card_ok = card.branch_count <= MAX_BRANCHES && positive(field0_v_per_um);
        for (i, br) in card.branches().iter().enumerate() {
            law.g[i] = R::from_f64(br.g_mpa);
            law.tau[i] = R::from_f64(br.tau_s);
            card_ok &= non_negative(law.g[i]) && positive(law.tau[i]);
        }
        if !card_ok {
            return Err(Error::Param { name: "card", range: "<= 3 branches, G >= 0, tau > 0, E_B > 0" });
        }
        Ok(law)
    }

    /// The breakdown field at thickness stretch s, V/mm (flat: `Breakdown`).
    pub fn breakdown_field(&self, _s: R) -> R {
        self.field0_v_per_mm
    }

    /// The voltage of the breakdown field across the film at stretch s, V: `E_B(s) s z0`.
    pub fn breakdown_volts(&self, s: R) -> R {
        self.breakdown_field(s) * s * self.z0
    }

    /// beta = eps V^2 / z0^2, MPa.
    fn beta(&self, volts: R) -> R {
        self.eps * volts * volts / (self.z0 * self.z0)
    }

    /// The voltage of a film stress `f`, V (`f >= 0`).
    fn volts_of(&self, f: R) -> R {
        self.z0 * (f / self.eps).sqrt()
    }
}

/// Finite and > 0 (`StackLaw::with_film`'s checks).
fn positive<R: Real>(x: R) -> bool {
    finite_sign(x, false)
}

/// Finite and >= 0.
fn non_negative<R: Real>(x: R) -> bool {
    finite_sign(x, true)
}

/// Finite and > 0, or 0 when `zero_ok`. Out of line: the check stays in R (a card's f64 value
/// converted first), no f64 compare on a target without a double-precision FPU.
#[inline(never)]
fn finite_sign<R: Real>(x: R, zero_ok: bool) -> bool {
    x.is_finite() && (x > R::zero() || (zero_ok && x == R::zero()))
}

/// One layer's state: the branches' a_i (1 at rest) and the thickness stretch s now.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct StackState<R> {
    pub a: [R; MAX_BRANCHES],
    pub s: R,
    /// The low-order part of `a` the branch updates carry (compensated summation): an f32 `a`
    /// near 1 cannot take a slow branch's per-tick increment alone.
    pub a_lo: [R; MAX_BRANCHES],
}

impl<R: Real> StackState<R> {
    /// The film at rest, unstretched and relaxed.
    pub fn rest() -> Self {
        StackState { a: [R::one(); MAX_BRANCHES], s: R::one(), a_lo: [R::zero(); MAX_BRANCHES] }
    }

    /// One tick at `volts` without a guard: the thickness now (warm-started Newton), then the
    /// branches relax over the step at that thickness.
    pub fn advance(&mut self, law: &StackLaw<R>, relaxation: &Relaxation<R>, volts: R) -> Result<(), Error> {
        self.s = ratio_at_voltage(law, &self.a, volts, self.s)?;
        relaxation.relax(self);
        Ok(())
    }
}

/// The film balance at frozen branches: `P s - Q s^4`.
#[derive(Clone, Copy, Debug)]
struct Balance<R> {
    p: R,
    q: R,
}

impl<R: Real> Balance<R> {
    fn of(law: &StackLaw<R>, a: &[R; MAX_BRANCHES]) -> Self {
        let (mut p, mut q) = (law.g_eq, law.g_eq);
        for i in 0..law.branches.min(MAX_BRANCHES) {
            p += law.g[i] / a[i];
            q += law.g[i] * a[i] * a[i];
        }
        Balance { p, q }
    }

    /// At equilibrium (a_i = 1/s) the branches carry nothing.
    fn relaxed(law: &StackLaw<R>) -> Self {
        Balance { p: law.g_eq, q: law.g_eq }
    }

    fn stress(&self, s: R) -> R {
        let s3 = s * s * s;
        s * (self.p - self.q * s3)
    }

    fn slope(&self, s: R) -> R {
        self.p - R::from_f64(4.0) * self.q * s * s * s
    }

    /// Where the stable branch ends: s_pi^3 = P / (4 Q).
    fn pull_in(&self) -> R {
        (self.p / (R::from_f64(4.0) * self.q)).cbrt()
    }

    /// The root of `stress(s) = beta` on the stable branch, Newton from `s_start` when it lies
    /// on the stable branch at or right of the root (the previous tick's thickness under a
    /// voltage that did not fall), else from 1: f is concave, so from the right the iterates
    /// fall monotonically onto the root. `None` past pull-in.
    fn solve(&self, beta: R, s_start: R) -> Result<R, Refusal> {
        if !beta.is_finite() {
            return Err(Refusal::NotConverged);
        }
        // warm start where the branch is stable (slope < 0) at or right of the root
        let mut s = R::one();
        if s_start > R::zero() && s_start < R::one() && self.slope(s_start) < R::zero() && self.stress(s_start) <= beta {
            s = s_start;
        }
        let tol = R::from_f64(4.0 * R::EPS);
        for k in 0..MAX_NEWTON {
            let d = self.slope(s);
            // past the end of the stable branch without meeting the root: beta is past pull-in
            if !(d < R::zero()) {
                return Err(Refusal::PullIn);
            }
            let step = (self.stress(s) - beta) / d;
            // after the first step the iterates lie right of the root and only fall: a step
            // that does not is rounding noise (near pull-in it exceeds `tol`)
            if k > 0 && !(step > R::zero()) {
                return Ok(s);
            }
            s -= step;
            if !s.is_finite() {
                return Err(Refusal::NotConverged);
            }
            if step.abs() <= tol * s {
                // the root of a beta just past the peak in rounding would lie left of it
                return if self.slope(s) < R::zero() { Ok(s) } else { Err(Refusal::PullIn) };
            }
        }
        Err(Refusal::NotConverged)
    }
}

const MAX_NEWTON: u32 = 60;

enum Refusal {
    PullIn,
    NotConverged,
}

impl Refusal {
    /// The typed error; `pull_in_volts` (the balance's pull-in voltage) is asked only past it.
    fn error<R: Real>(self, volts: R, pull_in_volts: impl FnOnce() -> R) -> Error {
        match self {
            Refusal::PullIn => Error::PullIn { volts: volts.to_f64(), pull_in: pull_in_volts().to_f64() },
            Refusal::NotConverged => Error::NotConverged { iterations: MAX_NEWTON, residual: f64::INFINITY },
        }
    }
}

/// The film stress `f(s; a)`, MPa (film balance: `f = beta` holds the film at s).
pub fn film_stress<R: Real>(law: &StackLaw<R>, a: &[R; MAX_BRANCHES], s: R) -> R {
    Balance::of(law, a).stress(s)
}

/// `df/ds` of the film balance, MPa (negative on the stable branch).
pub fn film_stress_slope<R: Real>(law: &StackLaw<R>, a: &[R; MAX_BRANCHES], s: R) -> R {
    Balance::of(law, a).slope(s)
}

/// Where the stable branch of the film balance ends for frozen branches `a`: `(P / 4Q)^(1/3)`.
pub fn pull_in_ratio<R: Real>(law: &StackLaw<R>, a: &[R; MAX_BRANCHES]) -> R {
    Balance::of(law, a).pull_in()
}

/// The film's incremental capacitance over its capacitance, `(dQ/dV) / (Q/V)`, at stretch `s`
/// with branches `a` frozen (a swing faster than the branches, such as the hold ripple): with
/// C = C0 / s², `d ln C / d ln V = -2 d ln s / d ln V = -4 f / (s f')`, so the ratio is
/// `1 - 4 f / (s f')` (above 1 on the stable branch). Refuses s outside (0, 1] and a stretch
/// past the branch's pull-in.
pub fn incremental_capacitance_ratio<R: Real>(law: &StackLaw<R>, a: &[R; MAX_BRANCHES], s: R) -> Result<R, Error> {
    if !(s > R::zero() && s <= R::one()) {
        return Err(Error::Input { input: "thickness ratio", reason: "must lie in (0, 1]" });
    }
    let b = Balance::of(law, a);
    let slope = b.slope(s);
    if !(slope < R::zero()) {
        return Err(Error::Input { input: "thickness ratio", reason: "past the film's pull-in" });
    }
    Ok(R::one() - R::from_f64(4.0) * b.stress(s) / (s * slope))
}

/// The voltage that holds the film at stretch `s` with branches `a` now, V (film balance in
/// closed form, `V = z0 sqrt(f / eps)`). Refuses s outside (0, 1] and a negative film stress
/// (the film is thinner than s at 0 V).
pub fn voltage_at_ratio<R: Real>(law: &StackLaw<R>, a: &[R; MAX_BRANCHES], s: R) -> Result<R, Error> {
    voltage_of_balance(law, &Balance::of(law, a), s)
}

fn voltage_of_balance<R: Real>(law: &StackLaw<R>, b: &Balance<R>, s: R) -> Result<R, Error> {
    if !s.is_finite() {
        return Err(Error::NonFinite { input: "thickness ratio" });
    }
    if !(s > R::zero() && s <= R::one()) {
        return Err(Error::Input { input: "thickness ratio", reason: "must lie in (0, 1]" });
    }
    let f = b.stress(s);
    if !(f >= R::zero()) {
        return Err(Error::Input { input: "thickness ratio", reason: "the film is thinner than that at 0 V" });
    }
    Ok(law.volts_of(f))
}

/// The thickness stretch at `volts` with branches `a` now, on the stable branch (Newton from
/// `s_start`, the previous tick's s). A typed error past the present state's pull-in.
pub fn ratio_at_voltage<R: Real>(law: &StackLaw<R>, a: &[R; MAX_BRANCHES], volts: R, s_start: R) -> Result<R, Error> {
    check_volts(volts)?;
    let b = Balance::of(law, a);
    b.solve(law.beta(volts), s_start).map_err(|r| r.error(volts, || law.volts_of(b.stress(b.pull_in()))))
}

/// The thickness stretch once fully relaxed at `volts` (a_i = 1/s): `G_eq (s - s^4) = beta`.
pub fn equilibrium_ratio<R: Real>(law: &StackLaw<R>, volts: R) -> Result<R, Error> {
    check_volts(volts)?;
    Balance::relaxed(law).solve(law.beta(volts), R::one()).map_err(|r| r.error(volts, || equilibrium_pull_in_voltage(law)))
}

/// The voltage that holds the film at `s` once fully relaxed, V.
pub fn equilibrium_voltage<R: Real>(law: &StackLaw<R>, s: R) -> Result<R, Error> {
    voltage_of_balance(law, &Balance::relaxed(law), s)
}

/// The equilibrium pull-in voltage, V (at s = 4^(-1/3)): no held voltage at or above it has an
/// equilibrium.
pub fn equilibrium_pull_in_voltage<R: Real>(law: &StackLaw<R>) -> R {
    law.volts_of(Balance::relaxed(law).stress(R::from_f64(EQUILIBRIUM_PULL_IN_RATIO)))
}

/// How a layer is held in its plane while a voltage thins it (docs/materials.md "Free film and
/// bonded stack: one law, two holds"): one incompressible neo-Hookean layer, its in-plane
/// stretches along the hinge `λ1 = s^(-(1-c)/2)` and across it `λ2 = s^(-(1+c)/2)` (λ1 λ2 s = 1),
/// the width's edges free (σ2 = 0). Relaxed, the balance is `G_eq (s^(1-c) - s^4) = beta`.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Hold {
    /// c = 0: free and equal-biaxial, `G_eq (s - s^4) = beta`. The hold ceiling's and the
    /// thinning guard's law: of the two it thins the most (the conservative side).
    FreeFilm,
    /// c = 1: bonded to the hinge's face, held along the hinge, free across its width (pure
    /// shear), `G_eq (1 - s^4) = beta`.
    Bonded,
    /// Bonded and held across its width too (plane strain along the hinge: a stack many times
    /// wider than it is thick, bonded on its face, is held across over most of its width): it
    /// does not thin (s = 1, incompressible); the voltage acts as the blocked in-plane stress
    /// `-beta` along the hinge and softens its tangent there from 4 G to 4 G - beta. The law
    /// of the stack's stiffness and its actuation in the solves ([`laminate_of_free_film`]).
    Laminate,
}

impl Hold {
    /// The share c of the layer's in-plane spread the hold takes away along the hinge (the
    /// laminate, held both ways, spreads nowhere: none).
    pub fn c(self) -> Option<f64> {
        match self {
            Hold::FreeFilm => Some(0.0),
            Hold::Bonded => Some(1.0),
            Hold::Laminate => None,
        }
    }
}

/// The relaxed film stress under `hold` at thickness stretch s, MPa: `G_eq (s^(1-c) - s^4)`.
pub fn held_stress<R: Real>(law: &StackLaw<R>, s: R, hold: Hold) -> R {
    match hold {
        Hold::FreeFilm => Balance::relaxed(law).stress(s),
        Hold::Bonded => {
            let s2 = s * s;
            law.g_eq * (R::one() - s2 * s2)
        }
        // held both ways the thickness carries no in-plane spread: the balance is s = 1 at any
        // beta (an infinite slope), its stress the Maxwell pressure the hold takes
        Hold::Laminate => {
            if s < R::one() {
                R::from_f64(f64::INFINITY)
            } else {
                R::zero()
            }
        }
    }
}

/// The thickness stretch once relaxed at `volts` under `hold`. `FreeFilm` is
/// [`equilibrium_ratio`] itself (the same code: the ceiling and the guard are unchanged).
/// `Bonded` has no pull-in before s = 0: `s = (1 - beta / G_eq)^(1/4)`, refused (as pull-in, at
/// the voltage of `beta = G_eq`) where the layer would thin to nothing.
pub fn held_equilibrium_ratio<R: Real>(law: &StackLaw<R>, volts: R, hold: Hold) -> Result<R, Error> {
    match hold {
        Hold::FreeFilm => equilibrium_ratio(law, volts),
        Hold::Bonded => {
            check_volts(volts)?;
            let x = R::one() - law.beta(volts) / law.g_eq;
            if !(x > R::zero()) {
                return Err(Error::PullIn { volts: volts.to_f64(), pull_in: law.volts_of(law.g_eq).to_f64() });
            }
            Ok(x.sqrt().sqrt())
        }
        Hold::Laminate => {
            check_volts(volts)?;
            Ok(R::one())
        }
    }
}

/// The layer's width stretch under `hold` at thickness stretch s: `λ2 = s^(-(1+c)/2)`
/// (volume kept: the section's area w t grows by 1/λ1 = s^((1-c)/2), 1 when bonded).
pub fn held_width_stretch<R: Real>(s: R, hold: Hold) -> R {
    match hold {
        Hold::FreeFilm => R::one() / s.sqrt(),
        Hold::Bonded => R::one() / s,
        Hold::Laminate => R::one(),
    }
}

/// The bonded layer's in-plane response along the hinge at `volts`, relaxed, at the bond's
/// stretch λ1 = 1 (docs/materials.md "Free film and bonded stack"): the blocked nominal stress
/// (MPa; negative: the layer pushes on the bond's ends) and the tangent modulus dP1/dλ1 at
/// fixed voltage (MPa). `Bonded` (width free): `G (1 - μ²)` and `G (1 + 3 μ² - μ⁶)`, μ = 1/s;
/// `Laminate` (width held): `-beta` and `4 G - beta`. A free film is not held along the hinge:
/// refused (`Input`).
pub fn held_axial<R: Real>(law: &StackLaw<R>, volts: R, hold: Hold) -> Result<(R, R), Error> {
    let g = law.g_eq;
    match hold {
        Hold::FreeFilm => Err(Error::Input { input: "hold", reason: "a free film is not held along the hinge" }),
        Hold::Bonded => {
            let s = held_equilibrium_ratio(law, volts, hold)?;
            let mu2 = R::one() / (s * s);
            Ok((g * (R::one() - mu2), g * (R::one() + R::from_f64(3.0) * mu2 - mu2 * mu2 * mu2)))
        }
        Hold::Laminate => {
            check_volts(volts)?;
            let beta = law.beta(volts);
            Ok((-beta, R::from_f64(4.0) * g - beta))
        }
    }
}

/// The laminate ([`Hold::Laminate`]) from the free film's relaxed thickness stretch `s_free`
/// at the same voltage (the solves' state of a stack: the thickness the guard watches, one to
/// one with the voltage on the stable branch): `b = beta / G = s - s⁴` (the free-film
/// balance), the tangent's factor `1 - b/4` over its value at 0 V, and that factor's
/// derivative in `s_free`, `-(1 - 4 s³)/4`. Closed form, any scalar (the solves' kernel).
#[inline(always)]
pub fn laminate_of_free_film<R: Real>(s_free: R) -> (R, R, R) {
    let s3 = s_free * s_free * s_free;
    let b = s_free - s3 * s_free;
    let quarter = R::from_f64(0.25);
    (b, R::one() - quarter * b, (R::from_f64(4.0) * s3 - R::one()) * quarter)
}

/// `Balance::pull_in` relaxed, where P = Q: s_pi = 4^(-1/3) (a constant: no cube root on the
/// equilibrium path).
const EQUILIBRIUM_PULL_IN_RATIO: f64 = 0.629_960_524_947_436_6;

fn check_volts<R: Real>(volts: R) -> Result<(), Error> {
    if !volts.is_finite() {
        return Err(Error::NonFinite { input: "voltage" });
    }
    if volts < R::zero() {
        return Err(Error::Input { input: "voltage", reason: "must not be negative" });
    }
    Ok(())
}

/// The hold ceiling, V per layer: `margin min(V_eq(2/3), E_B(2/3) 2/3 z0)`, the largest
/// voltage that may be held forever: relaxed, the film stays above the 33 % limit and the field
/// below the breakdown field.
pub fn hold_ceiling<R: Real>(law: &StackLaw<R>, margin: R) -> R {
    let s = R::from_f64(LIMIT_RATIO);
    // V_eq(2/3) exists: G_eq (s - s^4) > 0 there
    let v_film = law.volts_of(Balance::relaxed(law).stress(s));
    margin * v_film.min(law.breakdown_volts(s))
}

/// s_hold: the thickness stretch at the hold ceiling (with the law's margin) once relaxed, the
/// thinnest a held voltage ever gets.
pub fn hold_ratio<R: Real>(law: &StackLaw<R>) -> Result<R, Error> {
    equilibrium_ratio(law, hold_ceiling(law, law.margin))
}

/// The largest voltage that keeps the film at or above `s_floor` now (closed form):
/// `min(V(a, max(s_floor, s_pi(a))), margin E_B(s_floor) s_floor z0)`, less a rounding guard of
/// a few ulps so that the Newton root of the result is not below `s_floor`. 0 V when even 0 V
/// leaves the film thinner than `s_floor`. The control tick's guard.
pub fn voltage_bound_now<R: Real>(law: &StackLaw<R>, state: &StackState<R>, s_floor: R) -> R {
    if !(s_floor.is_finite() && s_floor > R::zero()) {
        return R::zero();
    }
    let b = Balance::of(law, &state.a);
    let s_floor = s_floor.min(R::one());
    // a floor past the branch's end holds at most the pull-in voltage (cold path: a cube root)
    let s = if b.slope(s_floor) < R::zero() { s_floor } else { b.pull_in() };
    let v_film = voltage_of_balance(law, &b, s).unwrap_or(R::zero());
    let v_field = law.margin * law.breakdown_volts(s_floor);
    let v = v_film.min(v_field) * (R::one() - R::from_f64(64.0 * R::EPS));
    if v.is_finite() && v > R::zero() {
        v
    } else {
        R::zero()
    }
}

/// The control tick's rule for one channel: the voltage `requested` (the slewed setpoint, at
/// most the hold ceiling, or the shaped voltage) limited to `voltage_bound_now(state, s_floor)`;
/// the film's thickness now at the voltage applied; the branches relaxed over the tick.
/// Returns the voltage applied, V (0 for a NaN or negative request).
pub fn guarded_tick<R: Real>(law: &StackLaw<R>, relaxation: &Relaxation<R>, state: &mut StackState<R>, requested: R, s_floor: R) -> Result<R, Error> {
    let bound = voltage_bound_now(law, state, s_floor);
    let v = if requested > R::zero() { requested.min(bound) } else { R::zero() };
    state.s = ratio_at_voltage(law, &state.a, v, state.s)?;
    relaxation.relax(state);
    Ok(v)
}

/// Shaped actuation's voltage now: the voltage that holds the film at `s_target` with its
/// branches as they are (above the target's equilibrium voltage until the film has relaxed onto
/// it), V; 0 V when the film is thinner than the target even at 0 V. The caller caps it with
/// the supply and passes `s_target` as the floor of [`guarded_tick`].
pub fn shaped_voltage<R: Real>(law: &StackLaw<R>, state: &StackState<R>, s_target: R) -> R {
    voltage_at_ratio(law, &state.a, s_target).unwrap_or(R::zero())
}

/// The branch flow times 3 tau_i: `1/s - s^2 a_i^3` (given 1/s and s^2; zero when relaxed,
/// a_i = 1/s).
#[inline(always)]
pub fn branch_flow<R: Real>(inv_s: R, s2: R, a: R) -> R {
    inv_s - s2 * a * a * a
}

/// How [`Relaxation`] advances the branch flow over one step at a held thickness.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Integrator {
    /// Exponential Euler at the branch's relaxation rate 1/tau (the default):
    /// `a <- a + (1 - exp(-dt/tau)) tau da/dt`. Exact for the relaxation linearised at
    /// a* = 1/s, where it is `a* + (a - a*) exp(-dt/tau)`; unlike that linearised step it tends
    /// to the branch flow as dt -> 0, also far from a*.
    Exponential,
    /// Explicit Euler on the branch flow.
    Euler,
    /// Heun (explicit trapezoid) on the branch flow.
    Heun,
}

impl Integrator {
    pub const ALL: [Integrator; 3] = [Integrator::Exponential, Integrator::Euler, Integrator::Heun];

    pub fn name(self) -> &'static str {
        match self {
            Integrator::Exponential => "exponential",
            Integrator::Euler => "euler",
            Integrator::Heun => "heun",
        }
    }
}

/// The per-tick stepper of the branch flow, built once per (law, dt): the exponential step's
/// factors exp(-dt/tau_i) are computed here, never per tick.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Relaxation<R> {
    pub integrator: Integrator,
    dt: R,
    /// 1 - exp(-dt/tau_i)
    one_minus_decay: [R; MAX_BRANCHES],
    /// dt / (3 tau_i)
    rate: [R; MAX_BRANCHES],
    branches: usize,
}

impl<R: Real> Relaxation<R> {
    /// The default (exponential) stepper of step `dt_s`.
    pub fn new(law: &StackLaw<R>, dt_s: R) -> Result<Self, Error> {
        Self::with_integrator(law, dt_s, Integrator::Exponential)
    }

    pub fn with_integrator(law: &StackLaw<R>, dt_s: R, integrator: Integrator) -> Result<Self, Error> {
        if !(dt_s.is_finite() && dt_s > R::zero()) {
            return Err(Error::Input { input: "time step", reason: "must be > 0 s" });
        }
        let mut one_minus_decay = [R::zero(); MAX_BRANCHES];
        let mut rate = [R::zero(); MAX_BRANCHES];
        for i in 0..law.branches.min(MAX_BRANCHES) {
            // 1 - e^-x, by its series where the subtraction would cancel
            let x = dt_s / law.tau[i];
            one_minus_decay[i] = if x < R::from_f64(1e-2) {
                x * (R::one() - x * (R::from_f64(0.5) - x * (R::from_f64(1.0 / 6.0) - x * R::from_f64(1.0 / 24.0))))
            } else {
                R::one() - (-x).exp()
            };
            rate[i] = dt_s / (R::from_f64(3.0) * law.tau[i]);
        }
        Ok(Relaxation { integrator, dt: dt_s, one_minus_decay, rate, branches: law.branches.min(MAX_BRANCHES) })
    }

    /// The step, s.
    pub fn dt(&self) -> R {
        self.dt
    }

    /// Advance the branches one step at the held thickness `state.s` (branch flow).
    pub fn relax(&self, state: &mut StackState<R>) {
        let s = state.s;
        let inv_s = R::one() / s;
        let s2 = s * s;
        let flow = |a: R| branch_flow(inv_s, s2, a);
        for i in 0..self.branches {
            let a = state.a[i];
            let delta = match self.integrator {
                Integrator::Exponential => self.one_minus_decay[i] * R::from_f64(1.0 / 3.0) * flow(a),
                Integrator::Euler => self.rate[i] * flow(a),
                Integrator::Heun => {
                    let k1 = flow(a);
                    let k2 = flow(a + self.rate[i] * k1);
                    self.rate[i] * R::from_f64(0.5) * (k1 + k2)
                }
            };
            // compensated (Kahan) addition of delta to a
            let y = delta - state.a_lo[i];
            let t = a + y;
            state.a_lo[i] = (t - a) - y;
            state.a[i] = t;
        }
    }
}

#[cfg(test)]
mod tests {
    use super::reference::advance_reference;
    use super::*;

    fn vhb<R: Real>() -> StackLaw<R> {
        StackLaw::new(&VHB_4905, R::from_f64(0.5), R::from_f64(0.9)).unwrap()
    }

    #[test]
    fn equilibrium_pull_in_at_4_to_the_minus_third() {
        for card in CARDS {
            let law = StackLaw::<f64>::new(card, 0.5, 0.9).unwrap();
            let v_pi = equilibrium_pull_in_voltage(&law);
            let s = equilibrium_ratio(&law, v_pi * (1.0 - 1e-9)).unwrap();
            assert!((s - 4f64.powf(-1.0 / 3.0)).abs() < 1e-3, "{}: {s}", card.name);
            assert!(matches!(equilibrium_ratio(&law, v_pi * (1.0 + 1e-9)), Err(Error::PullIn { .. })));
            // the slope of the balance vanishes there, and V_eq(s) peaks there
            let b = Balance::relaxed(&law);
            assert!(b.slope(4f64.powf(-1.0 / 3.0)).abs() < 1e-12);
            assert!((b.pull_in() - EQUILIBRIUM_PULL_IN_RATIO).abs() < 1e-15);
            let v = |s: f64| equilibrium_voltage(&law, s).unwrap();
            assert!(v(0.63) < v_pi && v(0.64) < v_pi);
        }
    }

    /// One law, two holds: the free film is `equilibrium_ratio` bit for bit (the ceiling and
    /// the guard's law unchanged); the bonded layer (pure shear) balances `G (1 - s^4) = beta`,
    /// thins less than the free film at every voltage up to the ceiling (VHB at its 5.4 kV
    /// ceiling: 0.891 against 0.818, the figures of issue 55), and keeps its section's area.
    #[test]
    fn the_bonded_layer_is_the_same_law_held_along_the_hinge_and_thins_less() {
        for card in CARDS {
            let law = StackLaw::<f64>::new(card, 0.5, 0.9).unwrap();
            let top = hold_ceiling(&law, law.margin);
            for i in 1..=20 {
                let v = top * f64::from(i) / 20.0;
                let free = held_equilibrium_ratio(&law, v, Hold::FreeFilm).unwrap();
                assert_eq!(free.to_bits(), equilibrium_ratio(&law, v).unwrap().to_bits());
                let bonded = held_equilibrium_ratio(&law, v, Hold::Bonded).unwrap();
                assert!(bonded > free && bonded < 1.0, "{} at {v}: bonded {bonded}, free {free}", card.name);
                for (h, s) in [(Hold::FreeFilm, free), (Hold::Bonded, bonded)] {
                    // the balance G (s^(1-c) - s^4) = beta, with c from the hold
                    let beta = law.eps * v * v / (law.z0 * law.z0);
                    let c = h.c().unwrap();
                    assert!((law.g_eq * (s.powf(1.0 - c) - s.powi(4)) - beta).abs() < 1e-12 * beta.max(law.g_eq), "{h:?}");
                    assert!((held_stress(&law, s, h) - beta).abs() < 1e-12 * beta.max(law.g_eq), "{h:?}");
                }
                // volume: the bonded section's area t w is kept, the free film's grows by s^-1/2
                assert!((bonded * held_width_stretch(bonded, Hold::Bonded) - 1.0).abs() < 1e-15);
                assert!((free * held_width_stretch(free, Hold::FreeFilm) - free.sqrt()).abs() < 1e-15);
            }
        }
        let law = vhb::<f64>();
        let top = hold_ceiling(&law, law.margin);
        let (free, bonded) = (equilibrium_ratio(&law, top).unwrap(), held_equilibrium_ratio(&law, top, Hold::Bonded).unwrap());
        assert!((free - 0.818).abs() < 1e-3 && (bonded - 0.891).abs() < 1e-3, "free {free}, bonded {bonded}");
        // the bonded layer thins to nothing only at beta = G: refused there, with a typed error
        let v_zero = law.z0 * (law.g_eq / law.eps).sqrt();
        assert!(matches!(held_equilibrium_ratio(&law, v_zero * (1.0 + 1e-9), Hold::Bonded), Err(Error::PullIn { .. })));
        assert!(held_equilibrium_ratio(&law, v_zero * (1.0 - 1e-6), Hold::Bonded).unwrap() < 0.05);
        assert!(matches!(held_equilibrium_ratio(&law, -1.0, Hold::Bonded), Err(Error::Input { .. })));
        assert!(matches!(held_equilibrium_ratio(&law, f64::NAN, Hold::Bonded), Err(Error::NonFinite { .. })));
    }

    /// The laminate (held along and across): the blocked stress and the tangent are the first
    /// and second derivatives in λ1 of its free enthalpy per reference volume at fixed voltage,
    /// `G/2 (λ1² + λ1⁻² − 2) − beta/2 λ1²` (plane strain, s = 1/λ1, the field V/(s z0)),
    /// taken here by central differences; the pure-shear `Bonded` layer's likewise, its width
    /// λ2 free (σ2 = 0 at each λ1, by bisection). `laminate_of_free_film` is the laminate at the
    /// free film's thickness of the same voltage; the free film is refused.
    #[test]
    fn the_laminates_blocked_stress_and_tangent_are_its_enthalpys_derivatives() {
        for card in CARDS {
            let law = StackLaw::<f64>::new(card, 0.5, 0.9).unwrap();
            let g = law.g_eq;
            let top = hold_ceiling(&law, law.margin);
            for i in 0..=10 {
                let v = top * f64::from(i) / 10.0;
                let beta = law.eps * v * v / (law.z0 * law.z0);
                // the laminate: Π(λ1) = W - beta/2 λ1²
                let pi = |l: f64| 0.5 * g * (l * l + 1.0 / (l * l) - 2.0) - 0.5 * beta * l * l;
                let h = 1e-4;
                let p1 = (pi(1.0 + h) - pi(1.0 - h)) / (2.0 * h);
                let k1 = (pi(1.0 + h) - 2.0 * pi(1.0) + pi(1.0 - h)) / (h * h);
                let (blocked, tangent) = held_axial(&law, v, Hold::Laminate).unwrap();
                assert!((blocked - p1).abs() < 1e-6 * g && (tangent - k1).abs() < 1e-5 * g, "{} {v}: {blocked} {p1} {tangent} {k1}", card.name);
                assert_eq!(held_equilibrium_ratio(&law, v, Hold::Laminate).unwrap(), 1.0);
                // the pure-shear layer: Π(λ1) = min over λ2 of W(λ1, λ2) - beta/2 (λ1 λ2)²
                let pi_ps = |l1: f64| {
                    let w = |l2: f64| 0.5 * g * (l1 * l1 + l2 * l2 + 1.0 / (l1 * l1 * l2 * l2) - 3.0) - 0.5 * beta * (l1 * l2).powi(2);
                    // dΠ/dλ2 = 0 on the stable side: bisection on the derivative
                    let dw = |l2: f64| (w(l2 + 1e-7) - w(l2 - 1e-7)) / 2e-7;
                    let (mut lo, mut hi) = (0.5, 1.6);
                    for _ in 0..200 {
                        let mid = 0.5 * (lo + hi);
                        if dw(mid) < 0.0 {
                            lo = mid;
                        } else {
                            hi = mid;
                        }
                    }
                    w(0.5 * (lo + hi))
                };
                let h = 1e-3;
                let p1 = (pi_ps(1.0 + h) - pi_ps(1.0 - h)) / (2.0 * h);
                let k1 = (pi_ps(1.0 + h) - 2.0 * pi_ps(1.0) + pi_ps(1.0 - h)) / (h * h);
                let (blocked, tangent) = held_axial(&law, v, Hold::Bonded).unwrap();
                assert!((blocked - p1).abs() < 1e-4 * g && (tangent - k1).abs() < 1e-2 * g, "bonded {} {v}: {blocked} {p1} {tangent} {k1}", card.name);
                // the laminate at the free film's thickness of the same voltage
                let s = equilibrium_ratio(&law, v).unwrap();
                let (b, kappa, dkappa) = laminate_of_free_film(s);
                assert!((b * g - beta).abs() < 1e-12 * g, "{} {v}", card.name);
                assert!((kappa - (4.0 * g - beta) / (4.0 * g)).abs() < 1e-12);
                let hs = 1e-6;
                let fd = (laminate_of_free_film(s + hs).1 - laminate_of_free_film(s - hs).1) / (2.0 * hs);
                assert!((dkappa - fd).abs() < 1e-8, "{dkappa} {fd}");
            }
            assert!(matches!(held_axial(&law, 1000.0, Hold::FreeFilm), Err(Error::Input { .. })));
            assert!(matches!(held_axial(&law, f64::NAN, Hold::Laminate), Err(Error::NonFinite { .. })));
        }
    }

    #[test]
    fn vhb_hold_ceiling_for_half_a_millimetre() {
        let law = vhb::<f64>();
        let v = hold_ceiling(&law, law.margin);
        assert!((5000.0..6500.0).contains(&v), "{v}");
        let s_hold = hold_ratio(&law).unwrap();
        assert!(s_hold > LIMIT_RATIO, "{s_hold}");
        // the f32 law agrees
        let law32 = vhb::<f32>();
        assert!((hold_ceiling(&law32, law32.margin) as f64 - v).abs() < 1e-3 * v);
        // the ceiling is bounded by both: the relaxed film at 2/3 and the breakdown field
        let s = LIMIT_RATIO;
        assert!(v <= 0.9 * equilibrium_voltage(&law, s).unwrap() * (1.0 + 1e-12));
        assert!(v <= 0.9 * law.breakdown_field(s) * s * 0.5 * (1.0 + 1e-12));
    }

    fn round_trip<R: Real>(tol: f64) {
        let law = vhb::<R>();
        let states = [[R::one(); MAX_BRANCHES], [R::from_f64(1.05), R::from_f64(1.1), R::from_f64(1.02)], [R::from_f64(1.2); MAX_BRANCHES]];
        for a in &states {
            let s_pi = pull_in_ratio(&law, a).to_f64();
            let mut s = 0.999;
            while s > s_pi + 0.01 {
                // (a film with relaxed branches is thinner than s at 0 V for s near 1)
                let v = voltage_at_ratio(&law, a, R::from_f64(s)).unwrap_or(R::zero());
                if v > R::zero() {
                    for start in [R::one(), R::from_f64(s + 0.05), R::from_f64(s - 0.001)] {
                        let back = ratio_at_voltage(&law, a, v, start).unwrap().to_f64();
                        assert!((back - s).abs() < tol, "{a:?} {s} {back}");
                    }
                    let v2 = voltage_at_ratio(&law, a, R::from_f64(s - 0.003)).unwrap();
                    let s2 = ratio_at_voltage(&law, a, v2, R::from_f64(s)).unwrap();
                    assert!((voltage_at_ratio(&law, a, s2).unwrap().to_f64() - v2.to_f64()).abs() < 1e3 * tol * v2.to_f64());
                }
                s -= 0.01;
            }
            let v_pi = voltage_at_ratio(&law, a, R::from_f64(s_pi)).unwrap();
            assert!(matches!(ratio_at_voltage(&law, a, v_pi * R::from_f64(1.001), R::one()), Err(Error::PullIn { .. })));
        }
    }

    #[test]
    fn voltage_and_ratio_invert_each_other() {
        round_trip::<f64>(1e-10);
        round_trip::<f32>(2e-5);
    }

    #[test]
    fn bad_input_is_a_typed_error() {
        let law = vhb::<f32>();
        let a = [1.0; MAX_BRANCHES];
        assert!(matches!(ratio_at_voltage(&law, &a, f32::NAN, 1.0), Err(Error::NonFinite { .. })));
        assert!(matches!(ratio_at_voltage(&law, &a, -1.0, 1.0), Err(Error::Input { .. })));
        assert!(matches!(ratio_at_voltage(&law, &a, f32::INFINITY, 1.0), Err(Error::NonFinite { .. })));
        assert!(voltage_at_ratio(&law, &a, 1.5).is_err());
        assert!(voltage_at_ratio(&law, &a, f32::NAN).is_err());
        assert!(voltage_at_ratio(&law, &[2.0; MAX_BRANCHES], 0.999).is_err()); // thinner at 0 V
        assert_eq!(voltage_at_ratio(&law, &a, 1.0).unwrap(), 0.0);
        assert!(StackLaw::<f32>::new(&VHB_4905, 0.0, 0.9).is_err());
        assert!(StackLaw::<f32>::new(&VHB_4905, 0.5, 1.5).is_err());
        assert!(Relaxation::new(&law, 0.0).is_err());
        assert_eq!(voltage_bound_now(&law, &StackState::rest(), f32::NAN), 0.0);
    }

    #[test]
    fn relaxation_converges_to_one_over_s() {
        for integrator in Integrator::ALL {
            let law = vhb::<f32>();
            let relax = Relaxation::with_integrator(&law, 0.01, integrator).unwrap();
            let mut st = StackState::rest();
            let v = 5000.0;
            let first = ratio_at_voltage(&law, &st.a, v, 1.0).unwrap();
            // 2000 s: many times the slowest creep time of the card (the softer the equilibrium
            // branch, the slower the last branch's creep)
            for _ in 0..200_000 {
                st.advance(&law, &relax, v).unwrap();
            }
            let s_eq = equilibrium_ratio(&law, v).unwrap();
            assert!(first > s_eq + 0.05, "creep: {first} -> {s_eq}");
            assert!((st.s - s_eq).abs() < 1e-4, "{integrator:?}: {} vs {s_eq}", st.s);
            for i in 0..3 {
                assert!((st.a[i] - 1.0 / st.s).abs() < 1e-4, "{integrator:?} {i}: {:?}", st.a);
            }
        }
    }

    /// Small strains: the law is the standard linear solid (one branch): under a constant
    /// stress beta the strain 1 - s creeps from beta/(3(G_eq+G1)) to beta/(3 G_eq) with the time
    /// tau (G_eq + G1) / G_eq.
    #[test]
    fn small_strain_limit_is_a_standard_linear_solid() {
        let card = Card {
            name: "sls",
            g_eq_mpa: 0.02,
            branches: [Branch { g_mpa: 0.03, tau_s: 1.5 }, Branch::NONE, Branch::NONE],
            branch_count: 1,
            eps_r: 4.8,
            breakdown: Breakdown { field0_v_per_um: 100.0 },
            rho_g_cm3: 1.0,
        };
        let law = StackLaw::<f64>::new(&card, 0.5, 0.9).unwrap();
        let (ge, g1, tau) = (0.02, 0.03, 1.5);
        let beta = 3.0 * ge * 1e-5; // 1e-5 strain at equilibrium
        let v = 0.5 * (beta / law.eps).sqrt();
        let (e0, einf, tc) = (beta / (3.0 * (ge + g1)), beta / (3.0 * ge), tau * (ge + g1) / ge);
        let mut st = StackState::rest();
        let dt = 0.01;
        for k in 0..2000 {
            let t = k as f64 * dt;
            let s = ratio_at_voltage(&law, &st.a, v, st.s).unwrap();
            let e_sls = einf - (einf - e0) * (-t / tc).exp();
            assert!(((1.0 - s) - e_sls).abs() < 1e-3 * e_sls, "t={t}: {} vs {e_sls}", 1.0 - s);
            advance_reference(&law, &mut st, v, dt, 4).unwrap();
        }
        // and the slope at rest is the instantaneous modulus 3 (G_eq + G1)
        assert!((film_stress_slope(&law, &[1.0; 3], 1.0) + 3.0 * (ge + g1)).abs() < 1e-15);
    }

    #[test]
    fn guard_keeps_the_film_at_its_floor() {
        let law = vhb::<f32>();
        let relax = Relaxation::new(&law, 0.001).unwrap();
        let s_hold = hold_ratio(&law).unwrap();
        let mut st = StackState::rest();
        // a commanded 9 kV, guarded: the film never goes below s_hold
        for _ in 0..200_000 {
            let v = 9000f32.min(voltage_bound_now(&law, &st, s_hold));
            st.s = ratio_at_voltage(&law, &st.a, v, st.s).unwrap();
            assert!(st.s >= s_hold, "{} < {s_hold}", st.s);
            assert!(v / (st.s * law.z0) <= law.margin * law.breakdown_field(st.s));
            relax.relax(&mut st);
        }
        assert!(st.s < s_hold + 1e-3, "reaches the floor: {}", st.s);
    }
}
