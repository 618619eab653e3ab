//! Independent planar large-deflection continuum reference of the finger (f64, host only).
//!
//! This plays the role Abaqus plays in the paper: a model of the *real* geometry
//! (elliptical notches of variable thickness, links as thick beams of the body
//! material, DE stacks as parallel layers bonded over each hinge, the cable as a
//! follower load through its guide holes) that shares no code with the
//! three-element model in `finger-model`.
//!
//! In short: the centreline is an extensible Kirchhoff elastica; the loads distal to a
//! section are known from the positions of the guide holes and the tip (4n + 2 unknowns),
//! so the elastica is integrated from the clamp with RK4 (hinges in the notch angle φ) and
//! Newton drives the holes' mismatch to zero, with the tension ramped by continuation. The
//! formulation, its equations and its convergence are in `docs/continuum.md`.

use std::fmt;

/// Plain f64 parameters, mirroring the names of docs/model.md "Geometry" (mm, N, MPa).
#[derive(Clone, Debug, PartialEq)]
pub struct ContinuumParams {
    /// Number of elements (joints).
    pub n: usize,
    /// Element pitch, node to node (mm).
    pub l: f64,
    /// Link thickness in the bending plane (mm).
    pub b: f64,
    /// Width out of the plane (mm).
    pub w: f64,
    /// Thinnest hinge section (mm).
    pub t_min: f64,
    /// Notch semi-axis along x; hinge length 2a (mm).
    pub a: f64,
    /// Body Young's modulus (MPa).
    pub e_b: f64,
    /// Cable offset from the centreline toward +y (mm).
    pub e: f64,
    /// DE layers per stack (informational: stack thickness is given directly).
    pub layers: usize,
    /// DE layer rest thickness (mm, informational).
    pub z0: f64,
    /// DE Young's modulus (MPa); docs/model.md: 2 G (1 + ν) = 1.788.
    pub e_de: f64,
    /// Use the plate (plane-strain) modulus E_b / (1 - nu_b²) for the body.
    pub plate: bool,
    /// Body Poisson ratio (used only when `plate`).
    pub nu_b: f64,
    /// Treat the links as rigid (for comparison with the three-element model).
    pub rigid_links: bool,
    /// A span at or below this length (mm) is reported as contact.
    pub contact_floor: f64,
}

impl Default for ContinuumParams {
    fn default() -> Self {
        ContinuumParams {
            n: 3,
            l: 27.0,
            b: 10.0,
            w: 20.0,
            t_min: 1.5,
            a: 5.0,
            e_b: 12.0,
            e: 5.0,
            layers: 4,
            z0: 0.5,
            e_de: 2.0 * 0.6 * (1.0 + 0.49),
            plate: false,
            nu_b: 0.45,
            rigid_links: false,
            contact_floor: 0.1,
        }
    }
}

impl ContinuumParams {
    /// Modulus of the body material in bending and stretching: E_b, or the plate
    /// modulus E_b / (1 - nu_b²) when `plate` is set.
    pub fn body_modulus(&self) -> f64 {
        if self.plate {
            self.e_b / (1.0 - self.nu_b * self.nu_b)
        } else {
            self.e_b
        }
    }

    /// Hinge length 2a.
    pub fn hinge_len(&self) -> f64 {
        2.0 * self.a
    }

    /// Notch thickness at x in [0, 2a] (docs/model.md "Geometry").
    pub fn notch_thickness(&self, x: f64) -> f64 {
        let u = ((x - self.a) / self.a).clamp(-1.0, 1.0);
        self.t_min + (self.b - self.t_min) * (1.0 - (1.0 - u * u).max(0.0).sqrt())
    }

    fn validate(&self) -> Result<(), ContinuumError> {
        let bad = |m: &str| Err(ContinuumError::InvalidInput(m.to_string()));
        let pos = [("l", self.l), ("b", self.b), ("w", self.w), ("t_min", self.t_min), ("a", self.a), ("e_b", self.e_b), ("e", self.e), ("e_de", self.e_de)];
        for (name, v) in pos {
            if !(v.is_finite() && v > 0.0) {
                return bad(&format!("{name} must be finite and > 0 (got {v})"));
            }
        }
        if self.n == 0 {
            return bad("n must be >= 1");
        }
        if self.t_min > self.b {
            return bad("t_min must not exceed b");
        }
        if 2.0 * self.a >= self.l {
            return bad("the hinge (2a) must be shorter than the pitch l");
        }
        if self.plate && !(self.nu_b >= 0.0 && self.nu_b < 0.5) {
            return bad("nu_b must be in [0, 0.5)");
        }
        if !(self.contact_floor.is_finite() && self.contact_floor >= 0.0) {
            return bad("contact_floor must be >= 0");
        }
        Ok(())
    }
}

/// Discretisation: RK4 steps per hinge (uniform in the notch angle φ ∈ [0, π],
/// x = a (1 - cos φ)) and per link (uniform in s).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct Discretisation {
    pub hinge_steps: usize,
    pub link_steps: usize,
}

impl Discretisation {
    pub const fn new(hinge_steps: usize, link_steps: usize) -> Self {
        Discretisation { hinge_steps, link_steps }
    }
    /// The same discretisation refined by an integer factor.
    pub fn refined(self, factor: usize) -> Self {
        Discretisation::new(self.hinge_steps * factor, self.link_steps * factor)
    }
}

impl Default for Discretisation {
    /// Converged in the joint angles (docs/continuum.md has the figures).
    fn default() -> Self {
        Discretisation::new(128, 32)
    }
}

/// A planar pose: position (mm) and angle of the centreline tangent (rad).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct Pose {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

/// One converged equilibrium.
#[derive(Clone, Debug)]
pub struct ContinuumSolution {
    /// Cable tension P (N).
    pub tension: f64,
    /// External tip force (N, base frame), applied at node n on the centreline.
    pub tip_force: [f64; 2],
    /// Poses of nodes 0..=n (node k: link k's distal end on the centreline).
    pub nodes: Vec<Pose>,
    /// Poses of the hinges' distal ends (= links' proximal ends), k = 1..=n.
    pub hinge_ends: Vec<Pose>,
    /// Joint angles psi_k - psi_{k-1} (hinge + link of element k), rad.
    pub joint_angles: Vec<f64>,
    /// Rotation across hinge k alone, rad.
    pub hinge_angles: Vec<f64>,
    /// Rotation across link k alone (its bending), rad.
    pub link_angles: Vec<f64>,
    /// Tip pose (= node n).
    pub tip: Pose,
    /// Span lengths |hole at node k-1 → link k's proximal hole| (mm).
    pub spans: Vec<f64>,
    /// Cable pulled in: rest length n·l minus the current length of spans and chords (mm).
    pub excursion: f64,
    /// Guide-hole positions: (proximal hole of link k, distal hole of link k), base frame.
    pub holes: Vec<([f64; 2], [f64; 2])>,
    /// Centreline samples (s, x, y, theta) at every integration step, for plots.
    pub centreline: Vec<[f64; 4]>,
    /// Continuation steps taken and total Newton iterations.
    pub continuation_steps: usize,
    pub newton_iterations: usize,
    /// Final fixed-point mismatch (mm, max norm).
    pub residual: f64,
}

/// Errors: no NaN is ever returned, a failure is one of these.
#[derive(Clone, Debug, PartialEq)]
pub enum ContinuumError {
    InvalidInput(String),
    /// Span `joint` (1-based) fell to `span` <= the floor at tension `tension`
    /// (the first converged continuation step where it happened).
    Contact {
        joint: usize,
        span: f64,
        tension: f64,
    },
    /// Newton failed even with the smallest continuation step, last converged tension given.
    NoConvergence {
        tension: f64,
    },
    /// A limit point (fold) of the load path between `from` and `to` (the ramped load:
    /// the tension, or the tip force's largest component when the tension is zero):
    /// the tangent det(∂g/∂z) changed sign, or fell below 1 % of its unloaded value
    /// where continuation could not go on.
    LimitPoint {
        from: f64,
        to: f64,
    },
}

impl fmt::Display for ContinuumError {
    fn fmt(&self, f: &mut fmt::Formatter<'_>) -> fmt::Result {
        match self {
            ContinuumError::InvalidInput(m) => write!(f, "invalid input: {m}"),
            ContinuumError::Contact { joint, span, tension } => {
                write!(f, "contact: span {joint} is {span:.4} mm (at or below the floor) at P = {tension:.4} N")
            }
            ContinuumError::NoConvergence { tension } => {
                write!(f, "no convergence past P = {tension:.4} N")
            }
            ContinuumError::LimitPoint { from, to } => {
                write!(f, "limit point (singular tangent) between {from:.6} and {to:.6} N")
            }
        }
    }
}

impl std::error::Error for ContinuumError {}

// ---------------------------------------------------------------------------
// Core: section law, resultants, RK4 integration of the elastica.
// ---------------------------------------------------------------------------

/// Section stiffness about the reference (body) centreline:
/// N = ea ε + bc κ,  M = bc ε + dd κ  (ε axial strain of the centreline, κ = θ').
#[derive(Clone, Copy, Debug)]
struct Section {
    ea: f64,
    bc: f64,
    dd: f64,
    /// Rigid segment: ε = κ = 0.
    rigid: bool,
    /// Inextensible: ε = 0, κ = M / dd (only used without coupling).
    inextensible: bool,
}

impl Section {
    fn strains(&self, n: f64, m: f64) -> (f64, f64) {
        if self.rigid {
            (0.0, 0.0)
        } else if self.inextensible {
            (0.0, m / self.dd)
        } else {
            let det = self.ea * self.dd - self.bc * self.bc;
            ((self.dd * n - self.bc * m) / det, (self.ea * m - self.bc * n) / det)
        }
    }
}

/// Resultant of all loads distal to a section: force `f` (base frame) and its
/// moment `m0` about the base origin. The moment about the section point r is
/// M = m0 - r × f.
#[derive(Clone, Copy, Debug)]
struct Resultant {
    f: [f64; 2],
    m0: f64,
}

impl Resultant {
    /// A force f whose line of action passes through p, plus another one.
    fn force_at(f: [f64; 2], p: [f64; 2]) -> Self {
        Resultant { f, m0: cross(p, f) }
    }
    fn plus(self, o: Resultant) -> Self {
        Resultant { f: [self.f[0] + o.f[0], self.f[1] + o.f[1]], m0: self.m0 + o.m0 }
    }
}

fn cross(a: [f64; 2], b: [f64; 2]) -> f64 {
    a[0] * b[1] - a[1] * b[0]
}

/// State along the centreline: x, y, theta.
type State = [f64; 3];

/// Derivative with respect to the reference arc length s.
fn rhs(st: &State, sec: &Section, r: &Resultant) -> State {
    let (c, s) = (st[2].cos(), st[2].sin());
    let m = r.m0 - (st[0] * r.f[1] - st[1] * r.f[0]);
    let n = r.f[0] * c + r.f[1] * s;
    let (eps, kap) = sec.strains(n, m);
    [(1.0 + eps) * c, (1.0 + eps) * s, kap]
}

/// A segment of the beam: how the section varies and how s maps to the
/// integration variable.
enum Segment {
    /// Uniform section over length `len`, integrated in s.
    Uniform { len: f64, sec: Section },
    /// Elliptical notch of semi-axis a, integrated in φ ∈ [0, π] with
    /// x = a (1 - cos φ), ds/dφ = a sin φ; optional parallel stack (e_de, t_k).
    Notch { a: f64, t_min: f64, b: f64, w: f64, e_body: f64, stack: Option<(f64, f64)> },
}

impl Segment {
    fn length(&self) -> f64 {
        match self {
            Segment::Uniform { len, .. } => *len,
            Segment::Notch { a, .. } => 2.0 * a,
        }
    }

    /// (s(u), ds/du, section) at integration variable u.
    fn at(&self, u: f64) -> (f64, f64, Section) {
        match self {
            Segment::Uniform { sec, .. } => (u, 1.0, *sec),
            Segment::Notch { a, t_min, b, w, e_body, stack } => {
                let (sn, cs) = u.sin_cos();
                let t = t_min + (b - t_min) * (1.0 - sn);
                let mut ea = e_body * w * t;
                let mut bc = 0.0;
                let mut dd = e_body * w * t * t * t / 12.0;
                if let Some((e_de, tk)) = *stack {
                    if tk > 0.0 {
                        // Parallel layer, centroid at y = -d, bonded (plane sections):
                        // the continuum limit of K = C_h^-1 + T^T C_de^-1 T.
                        let d = 0.5 * t_min + 0.5 * tk;
                        let a_de = w * tk;
                        ea += e_de * a_de;
                        bc += e_de * a_de * d;
                        dd += e_de * (w * tk * tk * tk / 12.0 + a_de * d * d);
                    }
                }
                (a * (1.0 - cs), a * sn, Section { ea, bc, dd, rigid: false, inextensible: false })
            }
        }
    }

    fn span(&self) -> f64 {
        match self {
            Segment::Uniform { len, .. } => *len,
            Segment::Notch { .. } => std::f64::consts::PI,
        }
    }
}

/// Integrates one segment with `steps` RK4 steps from `st`; if `rec` is given,
/// pushes (s0 + s, x, y, theta) after every step.
fn integrate(seg: &Segment, mut st: State, res: &Resultant, steps: usize, s0: f64, mut rec: Option<&mut Vec<[f64; 4]>>) -> State {
    let steps = steps.max(1);
    let h = seg.span() / steps as f64;
    let f = |u: f64, y: &State, c: f64| -> State {
        let (_, dsdu, sec) = seg.at(u);
        let d = rhs(y, &sec, res);
        let g = dsdu * c;
        [d[0] * g, d[1] * g, d[2] * g]
    };
    let add = |y: &State, k: &State, c: f64| -> State { [y[0] + c * k[0], y[1] + c * k[1], y[2] + c * k[2]] };
    for i in 0..steps {
        let u = i as f64 * h;
        // In the notch, RK4's quadrature of ds/dφ = a sin φ over the step is
        // Simpson's rule; rescale ds/dφ by 1 + O(h⁴) so that each step covers its
        // reference arc length a (cos u - cos(u + h)) exactly (order unchanged).
        let c = match seg {
            Segment::Notch { .. } => {
                let simpson = h / 6.0 * (u.sin() + 4.0 * (u + 0.5 * h).sin() + (u + h).sin());
                (u.cos() - (u + h).cos()) / simpson
            }
            Segment::Uniform { .. } => 1.0,
        };
        let k1 = f(u, &st, c);
        let k2 = f(u + 0.5 * h, &add(&st, &k1, 0.5 * h), c);
        let k3 = f(u + 0.5 * h, &add(&st, &k2, 0.5 * h), c);
        let k4 = f(u + h, &add(&st, &k3, h), c);
        for j in 0..3 {
            st[j] += h / 6.0 * (k1[j] + 2.0 * k2[j] + 2.0 * k3[j] + k4[j]);
        }
        if let Some(r) = rec.as_deref_mut() {
            let (s, _, _) = seg.at(u + h);
            r.push([s0 + s, st[0], st[1], st[2]]);
        }
    }
    st
}

fn offset_point(st: &State, e: f64) -> [f64; 2] {
    [st[0] - e * st[2].sin(), st[1] + e * st[2].cos()]
}

// ---------------------------------------------------------------------------
// Dense Newton on a fixed-point problem z = Φ(z).
// ---------------------------------------------------------------------------

/// Solves A x = b in place by Gaussian elimination with partial pivoting.
/// Returns det(A), or None if singular.
fn lu_solve(a: &mut [f64], b: &mut [f64], n: usize) -> Option<f64> {
    let mut sign = 1.0;
    for c in 0..n {
        let mut piv = c;
        for r in c + 1..n {
            if a[r * n + c].abs() > a[piv * n + c].abs() {
                piv = r;
            }
        }
        let pv = a[piv * n + c].abs();
        if pv.is_nan() || pv <= 1e-300 {
            return None;
        }
        if piv != c {
            for k in 0..n {
                a.swap(c * n + k, piv * n + k);
            }
            b.swap(c, piv);
            sign = -sign;
        }
        let p = a[c * n + c];
        sign *= p;
        for r in c + 1..n {
            let fct = a[r * n + c] / p;
            if fct != 0.0 {
                for k in c..n {
                    a[r * n + k] -= fct * a[c * n + k];
                }
                b[r] -= fct * b[c];
            }
        }
    }
    for c in (0..n).rev() {
        let mut s = b[c];
        for k in c + 1..n {
            s -= a[c * n + k] * b[k];
        }
        b[c] = s / a[c * n + c];
    }
    Some(sign)
}

struct NewtonOut {
    z: Vec<f64>,
    iters: usize,
    /// det(∂g/∂z) at the last Jacobian.
    det_sign: f64,
    residual: f64,
}

/// Newton on g(z) = Φ(z) - z with a forward-difference Jacobian.
fn newton<F>(phi: F, z0: &[f64], max_iter: usize) -> Option<NewtonOut>
where
    F: Fn(&[f64]) -> Option<Vec<f64>>,
{
    let n = z0.len();
    let mut z = z0.to_vec();
    let g_of = |z: &[f64]| -> Option<Vec<f64>> {
        let p = phi(z)?;
        let g: Vec<f64> = p.iter().zip(z).map(|(a, b)| a - b).collect();
        if g.iter().all(|v| v.is_finite()) {
            Some(g)
        } else {
            None
        }
    };
    let norm = |v: &[f64]| v.iter().fold(0.0f64, |m, x| m.max(x.abs()));
    let mut g = g_of(&z)?;
    for it in 0..max_iter {
        let mut jac = vec![0.0; n * n];
        for j in 0..n {
            let h = 1e-7 * (1.0 + z[j].abs());
            let mut zp = z.clone();
            zp[j] += h;
            let gp = g_of(&zp)?;
            for i in 0..n {
                jac[i * n + j] = (gp[i] - g[i]) / h;
            }
        }
        let mut dz: Vec<f64> = g.iter().map(|v| -v).collect();
        let det_sign = lu_solve(&mut jac, &mut dz, n)?;
        // Damped update: halve while the mismatch grows a lot.
        let g0 = norm(&g);
        let mut lam = 1.0;
        let (znew, gnew) = loop {
            let zt: Vec<f64> = z.iter().zip(&dz).map(|(a, d)| a + lam * d).collect();
            match g_of(&zt) {
                Some(gt) if norm(&gt) <= g0.max(1e-14) * 2.0 || lam < 1e-3 => break (zt, gt),
                _ if lam < 1e-3 => return None,
                _ => lam *= 0.5,
            }
        };
        let step = norm(&dz) * lam;
        z = znew;
        g = gnew;
        let r = norm(&g);
        let scale = 1.0 + norm(&z);
        if step < 1e-12 * scale && r < 1e-10 * scale {
            return Some(NewtonOut { z, iters: it + 1, det_sign, residual: r });
        }
        if r < 1e-13 * scale {
            return Some(NewtonOut { z, iters: it + 1, det_sign, residual: r });
        }
    }
    None
}

// ---------------------------------------------------------------------------
// The finger.
// ---------------------------------------------------------------------------

struct Finger<'a> {
    p: &'a ContinuumParams,
    disc: Discretisation,
    hinge: Vec<Segment>,
    link: Segment,
}

/// Everything the forward shot produces.
struct Shot {
    z: Vec<f64>,
    nodes: Vec<Pose>,
    hinge_ends: Vec<Pose>,
    centreline: Vec<[f64; 4]>,
}

impl<'a> Finger<'a> {
    fn new(p: &'a ContinuumParams, stack_mm: &[f64], disc: Discretisation) -> Result<Self, ContinuumError> {
        p.validate()?;
        if disc.hinge_steps == 0 || disc.link_steps == 0 {
            return Err(ContinuumError::InvalidInput("discretisation steps must be >= 1".into()));
        }
        let stacks: Vec<f64> = if stack_mm.is_empty() {
            vec![0.0; p.n]
        } else if stack_mm.len() == p.n {
            stack_mm.to_vec()
        } else {
            return Err(ContinuumError::InvalidInput(format!("stack_mm has {} entries, expected 0 or n = {}", stack_mm.len(), p.n)));
        };
        if let Some((k, t)) = stacks.iter().enumerate().find(|(_, t)| !(t.is_finite() && **t >= 0.0)) {
            return Err(ContinuumError::InvalidInput(format!("stack {} thickness {t} mm", k + 1)));
        }
        let eb = p.body_modulus();
        let hinge = stacks
            .iter()
            .map(|&tk| Segment::Notch { a: p.a, t_min: p.t_min, b: p.b, w: p.w, e_body: eb, stack: if tk > 0.0 { Some((p.e_de, tk)) } else { None } })
            .collect();
        let link = Segment::Uniform {
            len: p.l - 2.0 * p.a,
            sec: Section { ea: eb * p.w * p.b, bc: 0.0, dd: eb * p.w * p.b.powi(3) / 12.0, rigid: p.rigid_links, inextensible: false },
        };
        Ok(Finger { p, disc, hinge, link })
    }

    fn nz(&self) -> usize {
        4 * self.p.n + 2
    }

    /// The unloaded straight configuration's z.
    fn straight(&self) -> Vec<f64> {
        let p = self.p;
        let mut z = Vec::with_capacity(self.nz());
        for k in 0..p.n {
            let x0 = k as f64 * p.l;
            z.extend_from_slice(&[x0 + 2.0 * p.a, p.e, x0 + p.l, p.e]);
        }
        z.extend_from_slice(&[p.n as f64 * p.l, 0.0]);
        z
    }

    /// Forward shot: given hole and tip positions z, integrate from the clamp and
    /// return the positions the integrated shape puts them at.
    fn shoot(&self, z: &[f64], tension: f64, tip_force: [f64; 2], record: bool) -> Option<Shot> {
        let p = self.p;
        let n = p.n;
        let tip = [z[4 * n], z[4 * n + 1]];
        let tip_res = Resultant::force_at(tip_force, tip);
        let mut st: State = [0.0, 0.0, 0.0];
        let mut s0 = 0.0;
        let mut out = vec![0.0; self.nz()];
        let mut nodes = vec![Pose::default()];
        let mut hinge_ends = Vec::with_capacity(n);
        let mut cl = Vec::new();
        if record {
            cl.push([0.0, 0.0, 0.0, 0.0]);
        }
        let mut prev_hole = [0.0, p.e];
        for k in 0..n {
            let a_k = [z[4 * k], z[4 * k + 1]];
            let b_k = [z[4 * k + 2], z[4 * k + 3]];
            // Hinge k: P along span k (toward the hole at node k-1), through A_k.
            let sp = [prev_hole[0] - a_k[0], prev_hole[1] - a_k[1]];
            let ls = (sp[0] * sp[0] + sp[1] * sp[1]).sqrt();
            if ls.is_nan() || ls <= 1e-9 {
                return None;
            }
            let res_h = Resultant::force_at([tension * sp[0] / ls, tension * sp[1] / ls], a_k).plus(tip_res);
            st = integrate(&self.hinge[k], st, &res_h, self.disc.hinge_steps, s0, record.then_some(&mut cl));
            s0 += self.hinge[k].length();
            hinge_ends.push(Pose { x: st[0], y: st[1], theta: st[2] });
            let ah = offset_point(&st, p.e);
            out[4 * k] = ah[0];
            out[4 * k + 1] = ah[1];
            // Link k: P along the chord (toward A_k), through B_k.
            let ch = [a_k[0] - b_k[0], a_k[1] - b_k[1]];
            let lc = (ch[0] * ch[0] + ch[1] * ch[1]).sqrt();
            if lc.is_nan() || lc <= 1e-9 {
                return None;
            }
            let res_l = Resultant::force_at([tension * ch[0] / lc, tension * ch[1] / lc], b_k).plus(tip_res);
            st = integrate(&self.link, st, &res_l, self.disc.link_steps, s0, record.then_some(&mut cl));
            s0 += self.link.length();
            nodes.push(Pose { x: st[0], y: st[1], theta: st[2] });
            let bh = offset_point(&st, p.e);
            out[4 * k + 2] = bh[0];
            out[4 * k + 3] = bh[1];
            prev_hole = b_k;
        }
        out[4 * n] = st[0];
        out[4 * n + 1] = st[1];
        if !out.iter().all(|v| v.is_finite()) {
            return None;
        }
        Some(Shot { z: out, nodes, hinge_ends, centreline: cl })
    }

    fn spans(&self, z: &[f64]) -> Vec<f64> {
        let mut prev = [0.0, self.p.e];
        (0..self.p.n)
            .map(|k| {
                let a = [z[4 * k], z[4 * k + 1]];
                let d = ((a[0] - prev[0]).powi(2) + (a[1] - prev[1]).powi(2)).sqrt();
                prev = [z[4 * k + 2], z[4 * k + 3]];
                d
            })
            .collect()
    }

    fn newton_at(&self, z0: &[f64], tension: f64, tip: [f64; 2]) -> Option<NewtonOut> {
        newton(|z| self.shoot(z, tension, tip, false).map(|s| s.z), z0, 15)
    }
}

/// Continuation state: the last converged point on the load path
/// λ ↦ (λ P, F_fixed + λ F_tip).
struct Tracker<'f, 'a> {
    f: &'f Finger<'a>,
    tension: f64,
    tip: [f64; 2],
    tip_fixed: [f64; 2],
    lam: f64,
    z: Vec<f64>,
    prev: Option<(f64, Vec<f64>)>,
    /// det(∂g/∂z) at the last and at the first converged step.
    det_sign: Option<f64>,
    det_first: Option<f64>,
    steps: usize,
    iters: usize,
    residual: f64,
    dlam: f64,
}

enum StepEnd {
    Reached,
    Contact { joint: usize, span: f64, lam: f64 },
}

impl<'f, 'a> Tracker<'f, 'a> {
    fn new(f: &'f Finger<'a>, tension: f64, tip: [f64; 2]) -> Self {
        let scale = tension.max(tip[0].abs().max(tip[1].abs())).max(1e-300);
        Tracker {
            f,
            tension,
            tip,
            tip_fixed: [0.0, 0.0],
            lam: 0.0,
            z: f.straight(),
            prev: None,
            det_sign: None,
            det_first: None,
            steps: 0,
            iters: 0,
            residual: 0.0,
            dlam: (0.25 / scale).min(1.0),
        }
    }

    fn loads(&self, lam: f64) -> (f64, [f64; 2]) {
        (lam * self.tension, [self.tip_fixed[0] + lam * self.tip[0], self.tip_fixed[1] + lam * self.tip[1]])
    }

    fn predict(&self, lam: f64) -> Vec<f64> {
        match &self.prev {
            Some((lp, zp)) if self.lam > *lp => {
                let r = (lam - self.lam) / (self.lam - lp);
                self.z.iter().zip(zp).map(|(a, b)| a + r * (a - b)).collect()
            }
            _ => self.z.clone(),
        }
    }

    /// Tries one Newton solve at `lam`; Some((out, min span joint, span)) if converged
    /// and the step was small enough.
    fn attempt(&self, lam: f64) -> Option<NewtonOut> {
        let (t, tip) = self.loads(lam);
        let pred = self.predict(lam);
        let out = self.f.newton_at(&pred, t, tip)?;
        let jump = out.z.iter().zip(&self.z).fold(0.0f64, |m, (a, b)| m.max((a - b).abs()));
        if jump > 3.0 {
            return None;
        }
        Some(out)
    }

    fn accept(&mut self, lam: f64, out: NewtonOut) -> Result<(), ContinuumError> {
        if let Some(s) = self.det_sign {
            if s.signum() != out.det_sign.signum() {
                return Err(ContinuumError::LimitPoint { from: self.lam * self.tension, to: lam * self.tension });
            }
        }
        self.det_sign = Some(out.det_sign);
        self.det_first.get_or_insert(out.det_sign);
        self.prev = Some((self.lam, std::mem::take(&mut self.z)));
        self.z = out.z;
        self.lam = lam;
        self.steps += 1;
        self.iters += out.iters;
        self.residual = out.residual;
        Ok(())
    }

    fn min_span(&self, z: &[f64]) -> (usize, f64) {
        let s = self.f.spans(z);
        let v = s.iter().cloned().fold(f64::INFINITY, f64::min);
        // Ties (identical joints decouple to identical spans) go to the most proximal.
        let k = s.iter().position(|&x| x <= v + 1e-9).unwrap_or(0);
        (k + 1, v)
    }

    /// Advances to λ = target, stopping at the first converged step whose
    /// smallest span is at or below the contact floor.
    fn advance_to(&mut self, target: f64) -> Result<StepEnd, ContinuumError> {
        let floor = self.f.p.contact_floor;
        while self.lam < target {
            let lam = (self.lam + self.dlam).min(target);
            match self.attempt(lam) {
                Some(out) => {
                    let fast = out.iters <= 4;
                    let (joint, span) = self.min_span(&out.z);
                    if span <= floor {
                        return Ok(StepEnd::Contact { joint, span, lam });
                    }
                    self.accept(lam, out)?;
                    if fast {
                        self.dlam = (self.dlam * 1.5).min(1.0);
                    }
                }
                None => {
                    self.dlam *= 0.5;
                    if self.dlam < 1e-9 {
                        // Stuck: if the tangent has all but vanished, this is a fold
                        // of the load path (a limit point), not a numerical failure.
                        if let (Some(d), Some(d0)) = (self.det_sign, self.det_first) {
                            if d.abs() < 1e-2 * d0.abs() {
                                let from = self.lam * self.tension.max(self.tip[0].abs().max(self.tip[1].abs()));
                                let to = (self.lam + 2.0 * self.dlam) * self.tension.max(self.tip[0].abs().max(self.tip[1].abs()));
                                return Err(ContinuumError::LimitPoint { from, to });
                            }
                        }
                        return Err(ContinuumError::NoConvergence { tension: self.lam * self.tension });
                    }
                }
            }
        }
        Ok(StepEnd::Reached)
    }

    fn solution(&self) -> Result<ContinuumSolution, ContinuumError> {
        let (t, tip) = self.loads(self.lam);
        let shot = self.f.shoot(&self.z, t, tip, true).ok_or(ContinuumError::NoConvergence { tension: t })?;
        Ok(build_solution(self.f, &self.z, shot, t, tip, self.steps, self.iters, self.residual))
    }
}

#[allow(clippy::too_many_arguments)]
fn build_solution(f: &Finger, z: &[f64], shot: Shot, tension: f64, tip_force: [f64; 2], steps: usize, iters: usize, residual: f64) -> ContinuumSolution {
    let p = f.p;
    let n = p.n;
    let spans = f.spans(z);
    let mut joint_angles = Vec::with_capacity(n);
    let mut hinge_angles = Vec::with_capacity(n);
    let mut link_angles = Vec::with_capacity(n);
    let mut holes = Vec::with_capacity(n);
    let mut cable = 0.0;
    for k in 0..n {
        joint_angles.push(shot.nodes[k + 1].theta - shot.nodes[k].theta);
        hinge_angles.push(shot.hinge_ends[k].theta - shot.nodes[k].theta);
        link_angles.push(shot.nodes[k + 1].theta - shot.hinge_ends[k].theta);
        let a = [z[4 * k], z[4 * k + 1]];
        let b = [z[4 * k + 2], z[4 * k + 3]];
        holes.push((a, b));
        cable += spans[k] + ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt();
    }
    ContinuumSolution {
        tension,
        tip_force,
        tip: shot.nodes[n],
        nodes: shot.nodes,
        hinge_ends: shot.hinge_ends,
        joint_angles,
        hinge_angles,
        link_angles,
        spans,
        excursion: n as f64 * p.l - cable,
        holes,
        centreline: shot.centreline,
        continuation_steps: steps,
        newton_iterations: iters,
        residual,
    }
}

fn check_loads(tension: f64, tip_force: [f64; 2]) -> Result<(), ContinuumError> {
    if !(tension.is_finite() && tension >= 0.0) {
        return Err(ContinuumError::InvalidInput(format!("tension must be finite and >= 0 (a slack cable pushes nothing), got {tension}")));
    }
    if !tip_force.iter().all(|v| v.is_finite()) {
        return Err(ContinuumError::InvalidInput("tip force must be finite".into()));
    }
    Ok(())
}

/// Solves the finger under cable tension `tension` (N) and an external tip
/// force (N, base frame, applied at node n on the centreline), with DE stacks of
/// thickness `stack_mm[k]` (mm; empty slice or 0 = no stack) over hinge k.
/// Loads are ramped together by continuation from the straight finger.
pub fn solve(p: &ContinuumParams, tension: f64, stack_mm: &[f64], tip_force: [f64; 2], disc: Discretisation) -> Result<ContinuumSolution, ContinuumError> {
    check_loads(tension, tip_force)?;
    let f = Finger::new(p, stack_mm, disc)?;
    let mut tr = Tracker::new(&f, tension, tip_force);
    if tension == 0.0 && tip_force == [0.0, 0.0] {
        return tr.solution();
    }
    match tr.advance_to(1.0)? {
        StepEnd::Reached => tr.solution(),
        StepEnd::Contact { joint, span, lam, .. } => Err(ContinuumError::Contact { joint, span, tension: lam * tension }),
    }
}

/// Where the load path ends at contact.
#[derive(Clone, Debug)]
pub struct ClosingReport {
    /// Tension (N) at which the first span reaches the contact floor.
    pub tension: f64,
    /// Which span (1-based).
    pub joint: usize,
    /// The equilibrium there (span = floor to about 1e-6 mm).
    pub solution: ContinuumSolution,
}

/// Ramps the tension (with a fixed tip force) up to `p_max` and, if a span
/// reaches `p.contact_floor` on the way, locates that tension by bisection.
/// Returns Ok(None) if no span closes up to `p_max`.
pub fn closing_tension(
    p: &ContinuumParams,
    stack_mm: &[f64],
    tip_force: [f64; 2],
    disc: Discretisation,
    p_max: f64,
) -> Result<Option<ClosingReport>, ContinuumError> {
    check_loads(p_max, tip_force)?;
    let f = Finger::new(p, stack_mm, disc)?;
    // First the tip force alone (at zero tension), then the tension with the
    // tip force held fixed.
    let mut z0 = f.straight();
    if tip_force != [0.0, 0.0] {
        let mut pre = Tracker::new(&f, 0.0, tip_force);
        if let StepEnd::Contact { joint, span, .. } = pre.advance_to(1.0)? {
            return Err(ContinuumError::Contact { joint, span, tension: 0.0 });
        }
        z0 = pre.z;
    }
    let mut tr = Tracker::new(&f, p_max, [0.0, 0.0]);
    tr.tip_fixed = tip_force;
    tr.z = z0;
    tr.dlam = (0.25 / p_max.max(1e-300)).min(1.0);
    let (mut lo, mut hi) = match tr.advance_to(1.0)? {
        StepEnd::Reached => return Ok(None),
        StepEnd::Contact { lam, .. } => (tr.lam, lam),
    };
    let floor = p.contact_floor;
    let mut joint = 0;
    for _ in 0..200 {
        if (hi - lo) * p_max < 1e-10 {
            break;
        }
        let mid = 0.5 * (lo + hi);
        let out = tr.attempt(mid).ok_or(ContinuumError::NoConvergence { tension: tr.lam * p_max })?;
        let (j, span) = tr.min_span(&out.z);
        if span <= floor {
            hi = mid;
            joint = j;
        } else {
            tr.accept(mid, out)?;
            lo = mid;
            if (span - floor).abs() < 1e-7 {
                joint = j;
                break;
            }
        }
    }
    if joint == 0 {
        joint = tr.min_span(&tr.z).0;
    }
    let solution = tr.solution()?;
    Ok(Some(ClosingReport { tension: lo * p_max, joint, solution }))
}

// ---------------------------------------------------------------------------
// Lower level: a uniform cantilever under dead end loads (closed-form checks).
// ---------------------------------------------------------------------------

/// A uniform cantilever clamped at the origin along +x.
#[derive(Clone, Copy, Debug)]
pub struct UniformBeam {
    pub length: f64,
    /// Bending stiffness E I (N·mm²).
    pub ei: f64,
    /// Axial stiffness E A (N); None = inextensible.
    pub ea: Option<f64>,
}

/// Shape of a uniform cantilever.
#[derive(Clone, Debug)]
pub struct BeamShape {
    /// (s, x, y, theta) at s = 0 and after every step.
    pub points: Vec<[f64; 4]>,
    pub tip: Pose,
}

/// Large-deflection shape of a uniform cantilever under a dead tip force
/// (base frame, N) and a tip moment (N·mm, counter-clockwise), with `steps` RK4
/// steps. The tip position is found by Newton with load continuation.
pub fn uniform_cantilever(beam: &UniformBeam, tip_force: [f64; 2], tip_moment: f64, steps: usize) -> Result<BeamShape, ContinuumError> {
    if !(beam.length > 0.0 && beam.ei > 0.0 && beam.ea.is_none_or(|v| v > 0.0)) || steps == 0 {
        return Err(ContinuumError::InvalidInput("beam length, EI, EA and steps must be > 0".into()));
    }
    if !(tip_force.iter().all(|v| v.is_finite()) && tip_moment.is_finite()) {
        return Err(ContinuumError::InvalidInput("loads must be finite".into()));
    }
    let sec = Section { ea: beam.ea.unwrap_or(1.0), bc: 0.0, dd: beam.ei, rigid: false, inextensible: beam.ea.is_none() };
    let seg = Segment::Uniform { len: beam.length, sec };
    let shoot = |z: &[f64], lam: f64, rec: Option<&mut Vec<[f64; 4]>>| -> Vec<f64> {
        let f = [lam * tip_force[0], lam * tip_force[1]];
        let res = Resultant { f, m0: cross([z[0], z[1]], f) + lam * tip_moment };
        let st = integrate(&seg, [0.0; 3], &res, steps, 0.0, rec);
        vec![st[0], st[1]]
    };
    let mut z = vec![beam.length, 0.0];
    let mut lam = 0.0;
    let mut dlam = 1.0f64;
    while lam < 1.0 {
        let target = (lam + dlam).min(1.0);
        match newton(|zz| Some(shoot(zz, target, None)), &z, 40) {
            Some(out) => {
                z = out.z;
                lam = target;
            }
            None => {
                dlam *= 0.5;
                if dlam < 1e-9 {
                    return Err(ContinuumError::NoConvergence { tension: lam });
                }
            }
        }
    }
    let mut pts = vec![[0.0; 4]];
    shoot(&z, 1.0, Some(&mut pts));
    let last = *pts.last().unwrap();
    Ok(BeamShape { tip: Pose { x: last[1], y: last[2], theta: last[3] }, points: pts })
}
