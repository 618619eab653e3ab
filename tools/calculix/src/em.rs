//! The electromechanical FE: the voltage applied to the stacks, not the model's thicknesses.
//!
//! Each DE layer carries the Maxwell stress of its field across its current thickness. The
//! layers are flat films of thickness z0 with reference normal N = e_y (the mesh's stack is
//! the lens that fills the notch under the waist; every point of it lies in some layer). At a
//! material point the layer's thickness stretch is `s = 1 / |F⁻ᵀ N|` (thickness = volume over
//! area, Nanson), its current normal `n = F⁻ᵀ N s`, the field `E = V / (s z0)` and the stress
//!
//! `T = ε0 εr E² n⊗n` (MPa with V in volts, z0 in mm, ε0 in F/m).
//!
//! That is the Maxwell tensor `ε (E⊗E − ½E² I)` plus the hydrostatic `½ ε E² I`, which an
//! incompressible film carries as pressure and does not feel; a free film under it has
//! `σ_y − σ_x = −ε E²`, the model's free-film balance (`material`). On a layer's boundary it is
//! the pair of pressures ε E² on its two electrode faces, pressing them together: the
//! "pressure pair on each layer's faces", taken point by point at the current thickness.
//!
//! CalculiX carries it as nodal forces `f_a = −∫ T ∇N_a dv` over the deformed stack elements
//! (20-node bricks, 3×3×3 Gauss points; s and n at each brick's centre), written as `*CLOAD`s; ccx solves the finger
//! (NLGEOM) under them and the other loads; the forces are recomputed on the deformed mesh and
//! the run repeated until they stop changing (a fixed point, Aitken-relaxed). At the fixed point
//! the forces are those of the stress on the geometry they deform: the coupled equilibrium.
//!
//! The film: the card's equilibrium shear modulus (`Params::stack_law`), neo-Hookean and
//! nearly incompressible ([`FILM_NU`]). The body: neo-Hookean (E_b, ν_b). 3D, half the width
//! (symmetry plane z = 0): the stack's side edge z = w/2 is free, so the bonded stack can thin
//! by spreading across the width (the model's free film spreads both ways).
//!
//! `FINGER_EM_TRACE=1` prints each run's update; `FINGER_CALCULIX_KEEP=1` keeps the decks.

use crate::ccx::{self, AnyMesh, FeError, Kind, Law};
use crate::mesh::{self, Density, Material, Mesh3, Segment};
use crate::{section_pose, stub_len, SectionPose};
use finger_model::material::{equilibrium_ratio, EPS0};
use finger_model::Params;
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// The film's Poisson ratio in the FE: nearly incompressible (bulk modulus ≈ 1000 G), so the
/// hydrostatic part of the Maxwell stress moves the thickness by ~1e-4 of the thinning.
pub const FILM_NU: f64 = 0.4995;

/// One layer's film: the card's equilibrium shear modulus, MPa, ε0 εr (F/m), z0 (mm).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Film {
    pub g_mpa: f64,
    pub eps: f64,
    pub z0_mm: f64,
}

impl Film {
    /// The parameter set's film (its `stack_law`: g_eq = E_de / (2 (1 + ν)), εr, z0). Refuses a
    /// set with gravity on (the FE has no body load).
    pub fn of(p: &Params<f64>) -> Result<Film, FeError> {
        if p.grav != 0.0 {
            return Err(FeError::Mesh("gravity is not in the electromechanical FE: set grav=0".into()));
        }
        let law = p.stack_law().map_err(|e| FeError::Mesh(format!("stack law: {e:?}")))?;
        Ok(Film { g_mpa: law.g_eq, eps: EPS0 * p.eps_r, z0_mm: p.z0 })
    }

    /// The Maxwell pressure at thickness stretch s, MPa: ε (V / (s z0))².
    pub fn pressure(&self, volts: f64, s: f64) -> f64 {
        let e = volts / (s * self.z0_mm);
        self.eps * e * e
    }

    /// Young's modulus of the FE's film, MPa.
    pub fn e_mpa(&self) -> f64 {
        2.0 * self.g_mpa * (1.0 + FILM_NU)
    }
}

/// The fixed point's stopping rule and budget.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FixedPoint {
    /// Stop when the forces' update is below this fraction of their size (2-norm).
    pub rtol: f64,
    pub max_iter: usize,
}

impl Default for FixedPoint {
    fn default() -> Self {
        FixedPoint { rtol: 1e-7, max_iter: 40 }
    }
}

// ---- the 20-node brick (CalculiX C3D20 order) ------------------------------------------------

/// Natural coordinates of the 20 nodes: corners ζ = −1 (1-4) and +1 (5-8), the midsides of the
/// bottom (9-12) and top (13-16) faces, the vertical edges (17-20).
const NAT: [[f64; 3]; 20] = [
    [-1.0, -1.0, -1.0],
    [1.0, -1.0, -1.0],
    [1.0, 1.0, -1.0],
    [-1.0, 1.0, -1.0],
    [-1.0, -1.0, 1.0],
    [1.0, -1.0, 1.0],
    [1.0, 1.0, 1.0],
    [-1.0, 1.0, 1.0],
    [0.0, -1.0, -1.0],
    [1.0, 0.0, -1.0],
    [0.0, 1.0, -1.0],
    [-1.0, 0.0, -1.0],
    [0.0, -1.0, 1.0],
    [1.0, 0.0, 1.0],
    [0.0, 1.0, 1.0],
    [-1.0, 0.0, 1.0],
    [-1.0, -1.0, 0.0],
    [1.0, -1.0, 0.0],
    [1.0, 1.0, 0.0],
    [-1.0, 1.0, 0.0],
];

/// ∂N_a/∂(ξ, η, ζ) of the serendipity brick at (ξ, η, ζ).
fn shape_grad(x: [f64; 3]) -> [[f64; 3]; 20] {
    let mut g = [[0.0; 3]; 20];
    for (a, n) in NAT.iter().enumerate() {
        let (xi, eta, zeta) = (x[0] * n[0], x[1] * n[1], x[2] * n[2]);
        if n[0] != 0.0 && n[1] != 0.0 && n[2] != 0.0 {
            // corner: (1+ξξa)(1+ηηa)(1+ζζa)(ξξa+ηηa+ζζa−2)/8
            let (p, q, r) = (1.0 + xi, 1.0 + eta, 1.0 + zeta);
            let s = xi + eta + zeta - 2.0;
            g[a] = [n[0] * q * r * (s + p) / 8.0, n[1] * p * r * (s + q) / 8.0, n[2] * p * q * (s + r) / 8.0];
        } else {
            // midside: the zero coordinate's factor is (1 − c²), the others (1 + c ca), /4
            let f = |i: usize| if n[i] == 0.0 { 1.0 - x[i] * x[i] } else { 1.0 + x[i] * n[i] };
            let df = |i: usize| if n[i] == 0.0 { -2.0 * x[i] } else { n[i] };
            g[a] = [df(0) * f(1) * f(2) / 4.0, f(0) * df(1) * f(2) / 4.0, f(0) * f(1) * df(2) / 4.0];
        }
    }
    g
}

fn det3(m: &[[f64; 3]; 3]) -> f64 {
    m[0][0] * (m[1][1] * m[2][2] - m[1][2] * m[2][1]) - m[0][1] * (m[1][0] * m[2][2] - m[1][2] * m[2][0]) + m[0][2] * (m[1][0] * m[2][1] - m[1][1] * m[2][0])
}

/// The inverse of a 3×3 matrix (None if singular).
fn inv3(m: &[[f64; 3]; 3]) -> Option<[[f64; 3]; 3]> {
    let d = det3(m);
    if !(d.abs() > 0.0) || !d.is_finite() {
        return None;
    }
    let mut r = [[0.0; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            let (i1, i2, j1, j2) = ((j + 1) % 3, (j + 2) % 3, (i + 1) % 3, (i + 2) % 3);
            r[i][j] = (m[i1][j1] * m[i2][j2] - m[i1][j2] * m[i2][j1]) / d;
        }
    }
    Some(r)
}

/// J[i][j] = Σ_a x_a[i] ∂N_a/∂ξ_j.
fn jacobian(x: &[[f64; 3]; 20], g: &[[f64; 3]; 20]) -> [[f64; 3]; 3] {
    let mut j = [[0.0; 3]; 3];
    for a in 0..20 {
        for r in 0..3 {
            for c in 0..3 {
                j[r][c] += x[a][r] * g[a][c];
            }
        }
    }
    j
}

const GAUSS3: [(f64, f64); 3] = [(-0.774_596_669_241_483_4, 5.0 / 9.0), (0.0, 8.0 / 9.0), (0.774_596_669_241_483_4, 5.0 / 9.0)];

/// A stack element's centre on the deformed mesh.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct FilmPoint {
    /// Reference position, mm.
    pub at: [f64; 3],
    /// Thickness stretch of the layer there.
    pub s: f64,
}

/// The Maxwell stress's nodal forces of one brick (reference nodes `x0`, deformed `x`) at
/// `volts`: `f_a = −∫ T ∇N_a dv`, and the brick's Gauss points.
fn brick_forces(film: &Film, volts: f64, x0: &[[f64; 3]; 20], x: &[[f64; 3]; 20]) -> Result<([[f64; 3]; 20], Vec<FilmPoint>), FeError> {
    // the layer's thickness stretch and normal, one per element (at its centre): T is constant
    // over the element, so its forces are the pressure pair on the element's faces; taken
    // point by point, the collapsed bricks where the lens ends (a singular map at one edge)
    // turn a displacement of their nodes into a spurious local thinning that feeds on itself
    let (s, n) = {
        let g = shape_grad([0.0; 3]);
        let (j0, j) = (jacobian(x0, &g), jacobian(x, &g));
        let Some(ji) = inv3(&j).filter(|_| det3(&j0) > 0.0) else {
            return Err(FeError::Mesh("a stack element turned singular".into()));
        };
        // F⁻ᵀ N = j⁻ᵀ j0ᵀ N, N = e_y: j0ᵀ e_y is row 1 of j0
        let m = [j0[1][0], j0[1][1], j0[1][2]];
        let mut v = [0.0; 3];
        for r in 0..3 {
            for k in 0..3 {
                v[r] += ji[k][r] * m[k];
            }
        }
        let s = 1.0 / (v[0] * v[0] + v[1] * v[1] + v[2] * v[2]).sqrt();
        (s, [v[0] * s, v[1] * s, v[2] * s])
    };
    let p = film.pressure(volts, s);
    let mut f = [[0.0; 3]; 20];
    for &(a, wa) in &GAUSS3 {
        for &(b, wb) in &GAUSS3 {
            for &(c, wc) in &GAUSS3 {
                let g = shape_grad([a, b, c]);
                let j = jacobian(x, &g);
                let Some(ji) = inv3(&j) else {
                    return Err(FeError::Mesh("a stack element turned singular".into()));
                };
                let dv = det3(&j) * wa * wb * wc;
                // ∇_x N_a = j⁻ᵀ ∂N_a/∂ξ; T ∇N_a = p n (n·∇N_a)
                for q in 0..20 {
                    let mut gx = [0.0; 3];
                    for r in 0..3 {
                        for k in 0..3 {
                            gx[r] += ji[k][r] * g[q][k];
                        }
                    }
                    let nd = n[0] * gx[0] + n[1] * gx[1] + n[2] * gx[2];
                    for r in 0..3 {
                        f[q][r] -= p * n[r] * nd * dv;
                    }
                }
            }
        }
    }
    let nat = shape_values([0.0; 3]);
    let mut at = [0.0; 3];
    for q in 0..20 {
        for r in 0..3 {
            at[r] += nat[q] * x0[q][r];
        }
    }
    Ok((f, vec![FilmPoint { at, s }]))
}

/// N_a at (ξ, η, ζ).
fn shape_values(x: [f64; 3]) -> [f64; 20] {
    let mut v = [0.0; 20];
    for (a, n) in NAT.iter().enumerate() {
        if n[0] != 0.0 && n[1] != 0.0 && n[2] != 0.0 {
            let (xi, eta, zeta) = (x[0] * n[0], x[1] * n[1], x[2] * n[2]);
            v[a] = (1.0 + xi) * (1.0 + eta) * (1.0 + zeta) * (xi + eta + zeta - 2.0) / 8.0;
        } else {
            let f = |i: usize| if n[i] == 0.0 { 1.0 - x[i] * x[i] } else { 1.0 + x[i] * n[i] };
            v[a] = f(0) * f(1) * f(2) / 4.0;
        }
    }
    v
}

/// The Maxwell forces of every stack element at its voltage (`volts_of(element centre x)`),
/// on the mesh displaced by `u` (node → (ux, uy, uz); missing: not displaced): (node, F) and the
/// Gauss points' thickness stretches.
pub fn maxwell_forces(
    film: &Film,
    mesh: &Mesh3,
    u: &BTreeMap<usize, [f64; 3]>,
    volts_of: &dyn Fn(f64) -> f64,
) -> Result<(BTreeMap<usize, [f64; 3]>, Vec<FilmPoint>), FeError> {
    let mut out: BTreeMap<usize, [f64; 3]> = BTreeMap::new();
    let mut pts = Vec::new();
    for (conn, mat) in &mesh.elems {
        if *mat != Material::Stack {
            continue;
        }
        let mut x0 = [[0.0; 3]; 20];
        let mut x = [[0.0; 3]; 20];
        for (k, &i) in conn.iter().enumerate() {
            x0[k] = mesh.nodes[i];
            let d = u.get(&i).copied().unwrap_or([0.0; 3]);
            x[k] = [x0[k][0] + d[0], x0[k][1] + d[1], x0[k][2] + d[2]];
        }
        let xc = conn.iter().map(|&i| mesh.nodes[i][0]).sum::<f64>() / 20.0;
        let volts = volts_of(xc);
        if volts == 0.0 {
            continue;
        }
        let (f, p) = brick_forces(film, volts, &x0, &x)?;
        for (k, &i) in conn.iter().enumerate() {
            let e = out.entry(i).or_insert([0.0; 3]);
            for r in 0..3 {
                e[r] += f[k][r];
            }
        }
        pts.extend(p);
    }
    Ok((out, pts))
}

// ---- the deck and the fixed point ------------------------------------------------------------

/// What holds the end face (a rigid face with a reference node) in one step.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum End {
    /// No end face (a whole finger's tip, or a free film).
    None,
    /// Free: no load on it.
    Free,
    /// Turned to this angle (rad) about z, translations free (a pure moment).
    Turned(f64),
}

/// One step of an electromechanical run (each starts where the one before ended).
#[derive(Clone, Debug, PartialEq)]
pub struct Step {
    pub end: End,
    /// Cable tension, N (only with guide holes).
    pub tension: f64,
    /// The Maxwell forces: this step's own, or those of an earlier step, frozen (dead loads:
    /// the stiffness without the field's dependence on the thickness).
    pub maxwell_from: Option<usize>,
}

/// A problem: mesh, which nodes are held, the film and its voltages.
pub struct Problem<'a> {
    pub p: &'a Params<f64>,
    pub mesh: Mesh3,
    pub film: Film,
    /// Volts of a stack element from its centre's x.
    pub volts_of: Box<dyn Fn(f64) -> f64 + 'a>,
    /// (node set name, nodes, dofs held at 0) besides the symmetry plane.
    pub held: Vec<(String, Vec<usize>, Vec<usize>)>,
    /// Nodes on z = 0 held in z (symmetry), excluding the end face's.
    pub sym: Vec<usize>,
    /// The rigid end face's nodes and its reference point (x, y).
    pub end_face: Option<(Vec<usize>, [f64; 2])>,
    /// Guide holes (node ids on z = 0) for the cable, in order.
    pub holes: Vec<usize>,
    pub out_nodes: Vec<usize>,
}

/// What one step ended at.
#[derive(Clone, Debug)]
pub struct StepResult {
    /// Displacements of the output nodes and every stack node.
    pub u: BTreeMap<usize, [f64; 3]>,
    /// The end face's reference node: rotation about z (rad) and the moment on it (N·mm, whole
    /// width), if there is an end face.
    pub end_rotation: f64,
    pub end_moment: f64,
    /// The stack's Gauss points at this step's fixed point.
    pub film: Vec<FilmPoint>,
}

/// The outcome of the fixed point.
#[derive(Clone, Debug)]
pub struct Solved {
    pub steps: Vec<StepResult>,
    pub iterations: usize,
    /// The last update of the forces over their size.
    pub update: f64,
}

fn stack_nodes(m: &Mesh3) -> Vec<usize> {
    let mut v: Vec<usize> = m.elems.iter().filter(|e| e.1 == Material::Stack).flat_map(|e| e.0.iter().copied()).collect();
    v.sort();
    v.dedup();
    v
}

fn node_set(s: &mut String, name: &str, nodes: &[usize]) {
    let _ = writeln!(s, "*NSET, NSET={name}");
    for &i in nodes {
        let _ = writeln!(s, "{},", i + 1);
    }
}

/// The deck for these steps and their Maxwell forces.
fn write_deck(pr: &Problem, steps: &[Step], forces: &[BTreeMap<usize, [f64; 3]>]) -> String {
    let mut s = String::new();
    let _ = writeln!(s, "*HEADING\nfinger-calculix: electromechanical, {}", Kind::Half3d.name());
    let mesh = AnyMesh::Three(pr.mesh.clone());
    let (blocks, mut next) = ccx::write_mesh(&mut s, Kind::Half3d, &mesh);
    let n_nodes = pr.mesh.nodes.len();
    // the end face's reference and rotation nodes (1-based ids past the mesh's)
    let (refn, rotn) = (n_nodes + 1, n_nodes + 2);
    if let Some((_, c)) = &pr.end_face {
        let _ = writeln!(s, "*NODE, NSET=NEND\n{refn}, {:.12e}, {:.12e}, 0.\n{rotn}, {:.12e}, {:.12e}, 0.", c[0], c[1], c[0], c[1]);
    }
    let springs = !pr.holes.is_empty();
    let cable = if springs { ccx::cable_springs(&mesh, &pr.holes) } else { Vec::new() };
    for (set, pairs, _) in &cable {
        let _ = writeln!(s, "*ELEMENT, TYPE=SPRINGA, ELSET={set}");
        for (a, b) in pairs {
            let _ = writeln!(s, "{next}, {}, {}", a + 1, b + 1);
            next += 1;
        }
    }
    let mut out = pr.out_nodes.clone();
    out.extend(stack_nodes(&pr.mesh));
    out.sort();
    out.dedup();
    node_set(&mut s, "NOUT", &out);
    node_set(&mut s, "NSYM", &pr.sym);
    for (name, nodes, _) in &pr.held {
        node_set(&mut s, name, nodes);
    }
    if let Some((face, _)) = &pr.end_face {
        node_set(&mut s, "NFACE", face);
        let _ = writeln!(s, "*RIGID BODY, NSET=NFACE, REF NODE={refn}, ROT NODE={rotn}");
    }
    ccx::material_law(&mut s, "BODY", pr.p.e_b, pr.p.nu_b, Law::NeoHooke);
    ccx::material_law(&mut s, "STACK", pr.film.e_mpa(), FILM_NU, Law::NeoHooke);
    for (set, mat) in &blocks {
        let name = if *mat == Material::Body { "BODY" } else { "STACK" };
        let _ = writeln!(s, "*SOLID SECTION, ELSET={set}, MATERIAL={name}");
    }
    if springs {
        let tmax = 1000.0;
        for (set, _, frac) in &cable {
            let f = Kind::Half3d.load_share() * frac * tmax;
            let _ = writeln!(s, "*SPRING, ELSET={set}, NONLINEAR\n0., -1.e4, 0.\n0., 1.e4, 0.\n{f:.9e}, -1.e4, {tmax:.1}\n{f:.9e}, 1.e4, {tmax:.1}");
        }
        let _ = writeln!(s, "*INITIAL CONDITIONS, TYPE=TEMPERATURE\nNALL, 0.");
    }
    let _ = writeln!(s, "*BOUNDARY\nNSYM, 3, 3");
    for (name, _, dofs) in &pr.held {
        for d in dofs {
            let _ = writeln!(s, "{name}, {d}, {d}");
        }
    }
    if pr.end_face.is_some() {
        // symmetry: the face stays in its plane's normal, turns about z only
        let _ = writeln!(s, "{refn}, 3, 3\n{rotn}, 1, 2");
    }
    // the cable bends the finger far: ramp it; the voltage's steps take one increment if ccx can
    let inc = if springs { "0.25" } else { "1." };
    for (k, st) in steps.iter().enumerate() {
        // equilibrium to 1e-8 of the mean force (ccx's default, 5e-3, moves the hinge's
        // stiffness by ~0.1 %, the size of the voltage's effect on the board's finger)
        let _ = writeln!(s, "*STEP, NLGEOM, INC=2000\n*STATIC\n{inc}, 1., 1.e-6, 1.\n*CONTROLS, PARAMETERS=FIELD\n1.e-8, 1.e-6");
        if let End::Turned(th) = st.end {
            let _ = writeln!(s, "*BOUNDARY\n{rotn}, 3, 3, {th:.12e}");
        }
        if springs {
            let _ = writeln!(s, "*TEMPERATURE\nNALL, {:.9e}", st.tension);
        }
        let _ = writeln!(s, "*CLOAD, OP=NEW");
        let f = &forces[st.maxwell_from.unwrap_or(k)];
        for (i, v) in f {
            for r in 0..3 {
                if v[r] != 0.0 {
                    let _ = writeln!(s, "{}, {}, {:.12e}", i + 1, r + 1, v[r]);
                }
            }
        }
        let _ = writeln!(s, "*NODE PRINT, NSET=NOUT\nU");
        if pr.end_face.is_some() {
            let _ = writeln!(s, "*NODE PRINT, NSET=NEND\nU, RF");
        }
        let _ = writeln!(s, "*END STEP");
    }
    s
}

/// The `.dat` blocks whose header starts with `what` ("displacements", "forces"): per time,
/// node → 3 components.
fn blocks_of(dat: &str, what: &str) -> Vec<(f64, BTreeMap<usize, [f64; 3]>)> {
    let mut out: Vec<(f64, BTreeMap<usize, [f64; 3]>)> = Vec::new();
    let mut cur: Option<(f64, BTreeMap<usize, [f64; 3]>)> = None;
    for line in dat.lines() {
        let l = line.trim();
        if l.is_empty() {
            continue;
        }
        let f: Vec<&str> = l.split_whitespace().collect();
        if f.len() == 4 {
            if let (Some((_, map)), Ok(id), Ok(a), Ok(b), Ok(c)) =
                (cur.as_mut(), f[0].parse::<usize>(), f[1].parse::<f64>(), f[2].parse::<f64>(), f[3].parse::<f64>())
            {
                map.insert(id - 1, [a, b, c]);
                continue;
            }
        }
        if let Some(b) = cur.take() {
            out.push(b);
        }
        if l.starts_with(what) {
            if let Some(t) = l.rsplit(' ').next().and_then(|v| v.parse::<f64>().ok()) {
                cur = Some((t, BTreeMap::new()));
            }
        }
    }
    if let Some(b) = cur.take() {
        out.push(b);
    }
    out
}

/// The blocks at each step end (the last one printed at time k+1), merged by node.
fn at_step_ends(blocks: &[(f64, BTreeMap<usize, [f64; 3]>)], n: usize) -> Result<Vec<BTreeMap<usize, [f64; 3]>>, FeError> {
    (1..=n)
        .map(|k| {
            let t = k as f64;
            let mut m = BTreeMap::new();
            for b in blocks.iter().filter(|b| (b.0 - t).abs() < 1e-6 * t) {
                m.extend(b.1.iter().map(|(a, v)| (*a, *v)));
            }
            if m.is_empty() {
                Err(FeError::Parse(format!("no output at step end t = {t} (did the step converge?)")))
            } else {
                Ok(m)
            }
        })
        .collect()
}

/// Run ccx on the deck; (displacements per step, reaction forces per step).
fn run_deck(text: &str, n_steps: usize) -> Result<(Vec<BTreeMap<usize, [f64; 3]>>, Vec<BTreeMap<usize, [f64; 3]>>), FeError> {
    let dat = ccx::run_text(text)?;
    let u = at_step_ends(&blocks_of(&dat, "displacements"), n_steps)?;
    let f = blocks_of(&dat, "forces");
    let rf = if f.is_empty() { vec![BTreeMap::new(); n_steps] } else { at_step_ends(&f, n_steps)? };
    Ok((u, rf))
}

fn norm(f: &[BTreeMap<usize, [f64; 3]>]) -> f64 {
    f.iter().flat_map(|m| m.values()).flat_map(|v| v.iter()).map(|x| x * x).sum::<f64>().sqrt()
}

/// Solve the steps to the fixed point of the Maxwell forces (Aitken-relaxed iteration, every
/// step's forces one vector).
pub fn solve(pr: &Problem, steps: &[Step], fp: FixedPoint) -> Result<Solved, FeError> {
    for (k, st) in steps.iter().enumerate() {
        if st.maxwell_from.is_some_and(|j| j >= k) {
            return Err(FeError::Mesh(format!("step {k}: frozen forces must come from an earlier step")));
        }
        if k > 0 && st.end == End::Free && matches!(steps[k - 1].end, End::Turned(_)) {
            return Err(FeError::Mesh("a free end cannot follow a turned one (ccx keeps the boundary)".into()));
        }
    }
    let n = steps.len();
    let zero = BTreeMap::new();
    let (f0, _) = maxwell_forces(&pr.film, &pr.mesh, &zero, &*pr.volts_of)?;
    let mut x: Vec<BTreeMap<usize, [f64; 3]>> = vec![f0; n];
    let (mut r_prev, mut omega): (Option<Vec<BTreeMap<usize, [f64; 3]>>>, f64) = (None, 1.0);
    let mut update = f64::INFINITY;
    for it in 1..=fp.max_iter {
        let (u, rf) = run_deck(&write_deck(pr, steps, &x), n)?;
        // G(x): the forces on the deformed mesh of each step
        let mut gx = Vec::with_capacity(n);
        let mut films = Vec::with_capacity(n);
        for k in 0..n {
            let (f, pts) = maxwell_forces(&pr.film, &pr.mesh, &u[k], &*pr.volts_of)?;
            gx.push(f);
            films.push(pts);
        }
        // frozen steps keep their source's forces
        for k in 0..n {
            if let Some(j) = steps[k].maxwell_from {
                gx[k] = gx[j].clone();
            }
        }
        let r: Vec<BTreeMap<usize, [f64; 3]>> = (0..n)
            .map(|k| {
                gx[k]
                    .iter()
                    .map(|(i, g)| {
                        let xv = x[k].get(i).copied().unwrap_or([0.0; 3]);
                        (*i, [g[0] - xv[0], g[1] - xv[1], g[2] - xv[2]])
                    })
                    .collect()
            })
            .collect();
        let scale = norm(&gx).max(f64::MIN_POSITIVE);
        update = norm(&r) / scale;
        if std::env::var_os("FINGER_EM_TRACE").is_some() {
            let lo = films.iter().flatten().min_by(|a, b| a.s.total_cmp(&b.s));
            eprintln!("em: run {it}: update {update:.3e}, relaxation {omega:.3}, thinnest {lo:?}");
        }
        if update <= fp.rtol || scale <= f64::MIN_POSITIVE * 1e3 {
            let steps_out = (0..n)
                .map(|k| {
                    let (rot, mom) = if pr.end_face.is_some() {
                        let rotn = pr.mesh.nodes.len() + 1; // 0-based id of the ROT NODE
                        (u[k].get(&rotn).map_or(0.0, |v| v[2]), rf[k].get(&rotn).map_or(0.0, |v| v[2]) / Kind::Half3d.load_share())
                    } else {
                        (0.0, 0.0)
                    };
                    StepResult { u: u[k].clone(), end_rotation: rot, end_moment: mom, film: films[k].clone() }
                })
                .collect();
            return Ok(Solved { steps: steps_out, iterations: it, update });
        }
        // Aitken: ω_k = −ω_{k−1} r_{k−1}·(r_k − r_{k−1}) / |r_k − r_{k−1}|²
        if let Some(rp) = &r_prev {
            let (mut num, mut den) = (0.0, 0.0);
            for k in 0..n {
                for (i, v) in &r[k] {
                    let w = rp[k].get(i).copied().unwrap_or([0.0; 3]);
                    for c in 0..3 {
                        let d = v[c] - w[c];
                        num += w[c] * d;
                        den += d * d;
                    }
                }
            }
            if den > 0.0 {
                omega = (-omega * num / den).clamp(0.05, 2.0);
            }
        }
        for k in 0..n {
            for (i, v) in &r[k] {
                let e = x[k].entry(*i).or_insert([0.0; 3]);
                for c in 0..3 {
                    e[c] += omega * v[c];
                }
            }
        }
        r_prev = Some(r);
    }
    Err(FeError::Ccx(format!("the Maxwell forces did not settle in {} runs (update {update:.2e})", fp.max_iter)))
}

// ---- the problems --------------------------------------------------------------------------

/// A free film: one layer (z0 thick, 2 z0 square over the symmetry planes x = 0, y = 0, z = 0),
/// free in its plane, at `volts`. Its thickness stretch (the top face's) and the model's
/// free-film balance's (`equilibrium_ratio` of the set's `stack_law`).
pub fn free_film(p: &Params<f64>, volts: f64, fp: FixedPoint) -> Result<(f64, f64, Solved), FeError> {
    let film = Film::of(p)?;
    let z0 = p.z0;
    // a strip of thickness z0 (y in [−z0/2, z0/2]) from x = 0 to 2 z0, extruded to 2 z0
    let q = Params { b: z0, ..*p };
    let d = Density { notch_cols: 2, link_cols: 2, rows: 2, stack_rows: 1, layers: 2 };
    let m2 = mesh::mesh2(&q, &[Segment::Link { x0: 0.0, x1: 2.0 * z0 }], &d);
    let mut m3 = mesh::extrude(&m2, 2.0 * z0, d.layers);
    for e in &mut m3.elems {
        e.1 = Material::Stack;
    }
    let at = |f: &dyn Fn(&[f64; 3]) -> bool| (0..m3.nodes.len()).filter(|&i| f(&m3.nodes[i])).collect::<Vec<_>>();
    let x0 = at(&|n| n[0].abs() < 1e-9);
    let y0 = at(&|n| n[1].abs() < 1e-9);
    let sym = at(&|n| n[2].abs() < 1e-9);
    let top = at(&|n| (n[1] - z0 / 2.0).abs() < 1e-9);
    let pr = Problem {
        p,
        mesh: m3,
        film,
        volts_of: Box::new(move |_| volts),
        held: vec![("NX0".into(), x0, vec![1]), ("NY0".into(), y0, vec![2])],
        sym,
        end_face: None,
        holes: Vec::new(),
        out_nodes: top.clone(),
    };
    let sol = solve(&pr, &[Step { end: End::None, tension: 0.0, maxwell_from: None }], fp)?;
    let u = &sol.steps[0].u;
    let s_fe = top.iter().map(|i| 1.0 + u[i][1] / (z0 / 2.0)).sum::<f64>() / top.len() as f64;
    let law = p.stack_law().map_err(|e| FeError::Mesh(format!("stack law: {e:?}")))?;
    let s_model = equilibrium_ratio(&law, volts).map_err(|e| FeError::Mesh(format!("free-film balance: {e:?}")))?;
    Ok((s_fe, s_model, sol))
}

/// One hinge as `element_compliance` meshes it (a link stub clamped at x = −b, the notch with
/// its stack of `layers × z0` on [0, 2a], the link to x = l, a stub to l + b with a rigid end
/// face), its stack at `volts`.
pub fn hinge_problem<'a>(p: &'a Params<f64>, volts: f64, d: &Density) -> Result<Problem<'a>, FeError> {
    let s = stub_len(p);
    let t0 = f64::from(p.layers) * p.z0;
    let segs = [
        Segment::Link { x0: -s, x1: 0.0 },
        Segment::Notch { x0: 0.0, stack_mm: t0 },
        Segment::Link { x0: 2.0 * p.a, x1: p.l },
        Segment::Link { x0: p.l, x1: p.l + s },
    ];
    let m3 = mesh::extrude(&mesh::mesh2(p, &segs, d), p.w / 2.0, d.layers);
    let x_face = p.l + s;
    let clamp: Vec<usize> = m3.at_x(-s);
    let face: Vec<usize> = m3.at_x(x_face);
    let sym: Vec<usize> = (0..m3.nodes.len()).filter(|&i| m3.nodes[i][2].abs() < 1e-9 && !face.contains(&i)).collect();
    let mut out: Vec<usize> = m3.at_x(0.0).into_iter().chain(m3.at_x(p.l)).filter(|&i| m3.nodes[i][2].abs() < 1e-9).collect();
    out.sort();
    Ok(Problem {
        p,
        mesh: m3,
        film: Film::of(p)?,
        volts_of: Box::new(move |x| if (0.0..=2.0 * p.a).contains(&x) { volts } else { 0.0 }),
        held: vec![("NCLAMP".into(), clamp, vec![1, 2, 3])],
        sym,
        end_face: Some((face, [x_face, 0.0])),
        holes: Vec::new(),
        out_nodes: out,
    })
}

/// Section x's pose (its nodes on z = 0) in step `u`.
pub fn pose_at(mesh: &Mesh3, x: f64, u: &BTreeMap<usize, [f64; 3]>) -> SectionPose {
    let nodes: Vec<usize> = mesh.at_x(x).into_iter().filter(|&i| mesh.nodes[i][2].abs() < 1e-9).collect();
    let u2: BTreeMap<usize, [f64; 2]> = nodes.iter().map(|&i| (i, [u[&i][0], u[&i][1]])).collect();
    let plane = AnyMesh::Three(mesh.clone());
    section_pose(&plane, &nodes, &u2)
}

/// The hinge's rotation: section l's angle minus section 0's, rad.
pub fn hinge_rotation(pr: &Problem, u: &BTreeMap<usize, [f64; 3]>) -> f64 {
    pose_at(&pr.mesh, pr.p.l, u).theta - pose_at(&pr.mesh, 0.0, u).theta
}

/// One hinge at `volts`: under the voltage alone, then turned to a fixed rotation.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct HingeEm {
    /// The hinge's rotation under the voltage alone, rad (+: toward the cable side).
    pub rotation: f64,
    /// The layers' thickness stretch at mid-hinge under the voltage alone (mean over the stack
    /// elements of the column nearest x = a): towards the symmetry plane (z < w/4) and at the
    /// free side edge (z > w/4).
    pub s_mid_centre: f64,
    pub s_mid_edge: f64,
    /// The rotational stiffness at the fixed rotation, N·mm/rad, whole width: the end face turned
    /// to θ0 ∓ δ/2 (translations free: a pure moment), `k = ΔM / Δθ`, θ the hinge's rotation.
    pub k: f64,
    /// The hinge's rotation and the moment at the first of the two (θ0 − δ/2).
    pub turned: f64,
    pub moment: f64,
    pub iterations: usize,
}

/// The hinge at `volts`: the end free, then (a second fixed point) turned to θ0 − δ/2 and
/// θ0 + δ/2 about z.
pub fn hinge_em(p: &Params<f64>, volts: f64, theta0: f64, dtheta: f64, d: &Density, fp: FixedPoint) -> Result<HingeEm, FeError> {
    let pr = hinge_problem(p, volts, d)?;
    // two runs: ccx does not converge a turned end's first increment after a free step
    let free = solve(&pr, &[Step { end: End::Free, tension: 0.0, maxwell_from: None }], fp)?;
    let turned = [
        Step { end: End::Turned(theta0 - dtheta / 2.0), tension: 0.0, maxwell_from: None },
        Step { end: End::Turned(theta0 + dtheta / 2.0), tension: 0.0, maxwell_from: None },
    ];
    let sol = solve(&pr, &turned, fp)?;
    let free_u = &free.steps[0];
    // the stack elements of the column nearest mid-hinge
    let near = free_u.film.iter().map(|q| (q.at[0] - p.a).abs()).fold(f64::INFINITY, f64::min);
    let mean = |f: &dyn Fn(&FilmPoint) -> bool| {
        let v: Vec<f64> = free_u.film.iter().filter(|q| (q.at[0] - p.a).abs() <= near + 1e-6 && f(q)).map(|q| q.s).collect();
        if v.is_empty() {
            1.0
        } else {
            v.iter().sum::<f64>() / v.len() as f64
        }
    };
    let rot: Vec<f64> = sol.steps.iter().map(|s| hinge_rotation(&pr, &s.u)).collect();
    let m: Vec<f64> = sol.steps.iter().map(|s| s.end_moment).collect();
    Ok(HingeEm {
        rotation: hinge_rotation(&pr, &free_u.u),
        s_mid_centre: mean(&|q| q.at[2] < p.w / 4.0),
        s_mid_edge: mean(&|q| q.at[2] >= p.w / 4.0),
        k: (m[1] - m[0]) / (rot[1] - rot[0]),
        turned: rot[0],
        moment: m[0],
        iterations: free.iterations + sol.iterations,
    })
}

/// The whole finger (clamped at x = 0, the cable through its guide holes) with the voltages
/// per joint applied, at each tension (increasing): the joint angles per tension.
pub fn finger_under_cable_em(p: &Params<f64>, volts: &[f64], d: &Density, tensions: &[f64], fp: FixedPoint) -> Result<Vec<Vec<f64>>, FeError> {
    let t0 = f64::from(p.layers) * p.z0;
    let stack: Vec<f64> = (0..p.n).map(|_| t0).collect();
    let m3 = mesh::extrude(&mesh::mesh2(p, &mesh::finger_segments(p, &stack), d), p.w / 2.0, d.layers);
    let any = AnyMesh::Three(m3.clone());
    let mut holes = vec![any.find(0.0, p.e)?];
    for k in 0..p.n {
        let x0 = k as f64 * p.l;
        holes.push(any.find(x0 + 2.0 * p.a, p.e)?);
        holes.push(any.find(x0 + p.l, p.e)?);
    }
    let clamp = m3.at_x(0.0);
    let sym: Vec<usize> = (0..m3.nodes.len()).filter(|&i| m3.nodes[i][2].abs() < 1e-9).collect();
    let mut out: Vec<usize> = (0..=p.n).flat_map(|k| m3.at_x(k as f64 * p.l)).filter(|&i| m3.nodes[i][2].abs() < 1e-9).collect();
    out.extend(holes.iter().copied());
    out.sort();
    out.dedup();
    let vs = volts.to_vec();
    let pr = Problem {
        p,
        mesh: m3,
        film: Film::of(p)?,
        volts_of: Box::new(move |x| {
            let k = (x / p.l).floor();
            let u = x - k * p.l;
            if k >= 0.0 && (k as usize) < vs.len() && u <= 2.0 * p.a {
                vs[k as usize]
            } else {
                0.0
            }
        }),
        held: vec![("NCLAMP".into(), clamp, vec![1, 2, 3])],
        sym,
        end_face: None,
        holes,
        out_nodes: out,
    };
    let steps: Vec<Step> = tensions.iter().map(|&t| Step { end: End::None, tension: t, maxwell_from: None }).collect();
    let sol = solve(&pr, &steps, fp)?;
    Ok(sol
        .steps
        .iter()
        .map(|s| {
            let th: Vec<f64> = (0..=p.n).map(|k| pose_at(&pr.mesh, k as f64 * p.l, &s.u).theta).collect();
            th.windows(2).map(|w| w[1] - w[0]).collect()
        })
        .collect())
}

// ---- the model beside it -------------------------------------------------------------------

/// The model's one hinge (the finger's calibration, `Calibration::for_params`) at `volts`, its
/// stack the laminate (`Hold::Laminate`, `Finger::stack_held`), as `hinge_em` measures the FE:
/// its rotation under the voltage alone (rad, `Finger::voltage_rotation`) and its rotational
/// stiffness at a fixed rotation at 0 V over that at `volts` (`Σ C_θM`: the laminate's
/// softening; a pure moment, so the same at any rotation).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct ModelHinge {
    pub rotation: f64,
    pub ratio: f64,
}

pub fn model_hinge(p: &Params<f64>, volts: f64) -> Result<ModelHinge, String> {
    use finger_model::material::Hold;
    use finger_model::{Calibration, Finger, JointStiffness};
    let q = Params { n: 1, grav: 0.0, ..*p };
    let f = Finger::with_calibration(q, Calibration::for_params(p)).map_err(|e| e.to_string())?;
    let stack = f.stack_held(Hold::Laminate).map_err(|e| e.to_string())?;
    let (t0, t) = (f.stack_thickness(0.0).map_err(|e| e.to_string())?, f.stack_thickness(volts).map_err(|e| e.to_string())?);
    let c33 = |t: f64| -> Result<f64, String> {
        let k = JointStiffness::new(&f, &stack, t);
        (0..q.m).map(|j| k.compliance(j).map(|c| c[2][2]).map_err(|e| e.to_string())).sum()
    };
    Ok(ModelHinge { rotation: f.voltage_rotation(&stack, t).map_err(|e| e.to_string())?, ratio: c33(t)? / c33(t0)? })
}

/// A hinge of the FE-against-model table (`fe-em-table`, `em-hinges.txt`): a card and the
/// console parameters it sets.
#[derive(Clone, Copy, Debug)]
pub struct EmHinge {
    pub name: &'static str,
    pub card: &'static str,
    pub sets: &'static [(&'static str, f64)],
}

impl EmHinge {
    /// Its parameter set (without gravity: the FE has none).
    pub fn params(&self) -> Result<Params<f64>, String> {
        let card = finger_model::material::CARDS.iter().find(|c| c.name == self.card).ok_or(format!("card {}", self.card))?;
        let mut p = Params::with_card(card);
        crate::apply_overrides(&mut p, self.sets.iter().map(|(k, v)| (k.to_string(), *v)).collect())?;
        Ok(p)
    }
}

/// The board's finger, the design study's best VHB and Elastosil designs (`designs/`, without
/// their gravity) and a corner of the design space (the study's front design with the thickest
/// hinge and stiffest body, issue 55).
pub const EM_HINGES: [EmHinge; 4] = [
    EmHinge { name: "board", card: "VHB-4905", sets: &[] },
    EmHinge {
        name: "designs/VHB-4905",
        card: "VHB-4905",
        sets: &[("t_min", 0.5), ("a", 4.7), ("e_b", 12.0), ("w", 29.5), ("layers", 8.0), ("z0", 0.5), ("v_supply", 5500.0), ("margin", 0.9)],
    },
    EmHinge {
        name: "designs/Elastosil-2030",
        card: "Elastosil-2030",
        sets: &[("t_min", 0.5), ("a", 10.0), ("e_b", 40.0), ("w", 26.5), ("layers", 12.0), ("z0", 0.24), ("v_supply", 10250.0), ("margin", 0.9)],
    },
    EmHinge { name: "corner", card: "VHB-4905", sets: &[("t_min", 2.9), ("a", 2.6), ("e_b", 40.0), ("w", 30.0), ("layers", 7.0)] },
];
