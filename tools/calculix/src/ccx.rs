//! The CalculiX side: the input deck (`.inp`) for a mesh and its loads, running `ccx`, and
//! reading the nodal displacements it prints to the `.dat` file.
//!
//! What it is not: a finite-element solver. Every stiffness, Newton iteration and increment
//! is CalculiX's (2.20, Debian's `calculix-ccx`; scripts/setup installs it).

use crate::mesh::{Material, Mesh2, Mesh3};
use finger_model::Params;
use std::collections::BTreeMap;
use std::fmt::Write as _;
use std::path::PathBuf;
use std::process::Command;

/// The idealisation of the out-of-plane direction.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Kind {
    /// 2D, ε_z = 0 (CPE8R), thickness w.
    PlaneStrain,
    /// 2D plane stress (CPS8R), thickness w. CalculiX expands it to one slab of 20-node bricks
    /// of thickness w with free faces: a coarse 3D plate, not σ_z = 0 (see tests/beam.rs).
    PlaneStress,
    /// 3D, half the width (z in [0, w/2]) with the symmetry plane z = 0 (C3D20R).
    Half3d,
}

impl Kind {
    pub fn name(self) -> &'static str {
        match self {
            Kind::PlaneStrain => "plane strain (CPE8R)",
            Kind::PlaneStress => "plane stress (CPS8R)",
            Kind::Half3d => "3D half width (C3D20R)",
        }
    }
    pub fn short(self) -> &'static str {
        match self {
            Kind::PlaneStrain => "pe",
            Kind::PlaneStress => "ps",
            Kind::Half3d => "3d",
        }
    }
    /// The share of the whole finger's width this model carries (loads are scaled by it).
    pub fn load_share(self) -> f64 {
        if self == Kind::Half3d {
            0.5
        } else {
            1.0
        }
    }
}

#[derive(Debug)]
pub enum FeError {
    /// `ccx` could not be started (not installed: run scripts/setup).
    Spawn(String),
    /// `ccx` ran and reported an error or did not converge; the tail of its log.
    Ccx(String),
    /// The `.dat` did not hold what was asked for.
    Parse(String),
    /// The geometry asks for a node that the mesh has not (e.g. a guide hole off the grid).
    Mesh(String),
}

impl std::fmt::Display for FeError {
    fn fmt(&self, f: &mut std::fmt::Formatter<'_>) -> std::fmt::Result {
        match self {
            FeError::Spawn(s) => write!(f, "cannot run ccx ({s}); scripts/setup installs calculix-ccx"),
            FeError::Ccx(s) => write!(f, "ccx failed: {s}"),
            FeError::Parse(s) => write!(f, "ccx output: {s}"),
            FeError::Mesh(s) => write!(f, "mesh: {s}"),
        }
    }
}
impl std::error::Error for FeError {}

/// A mesh in either dimension, as the deck needs it.
pub enum AnyMesh {
    Two(Mesh2),
    Three(Mesh3),
}

impl AnyMesh {
    pub fn node_count(&self) -> usize {
        match self {
            AnyMesh::Two(m) => m.nodes.len(),
            AnyMesh::Three(m) => m.nodes.len(),
        }
    }
    pub fn xy(&self, i: usize) -> [f64; 2] {
        match self {
            AnyMesh::Two(m) => m.nodes[i],
            AnyMesh::Three(m) => [m.nodes[i][0], m.nodes[i][1]],
        }
    }
    pub fn at_x(&self, x: f64) -> Vec<usize> {
        match self {
            AnyMesh::Two(m) => m.at_x(x),
            AnyMesh::Three(m) => m.at_x(x),
        }
    }
    /// The node at (x, y) (on the symmetry plane z = 0 in 3D).
    pub fn find(&self, x: f64, y: f64) -> Result<usize, FeError> {
        match self {
            AnyMesh::Two(m) => m.find(x, y),
            AnyMesh::Three(m) => m.find(x, y, 0.0),
        }
        .ok_or_else(|| FeError::Mesh(format!("no node at ({x}, {y}): the guide holes must lie on a node row (e = b/2)")))
    }
    /// Elements, as (CalculiX node ids 1-based, material).
    pub fn element_count(&self) -> usize {
        match self {
            AnyMesh::Two(m) => m.elems.len(),
            AnyMesh::Three(m) => m.elems.len(),
        }
    }
}

/// The material law of the nonlinear (NLGEOM) cable runs. Both have the small-strain constants
/// (E, ν), so they agree at small loads and the linear unit loads need no choice.
#[derive(Clone, Copy, Debug, PartialEq, Eq, Hash)]
pub enum Law {
    /// Compressible neo-Hookean (`*HYPERELASTIC, NEO HOOKE`, C10 = G/2, D1 = 2/K): the
    /// elastomers' law at the waist's strains; the report's reference.
    NeoHooke,
    /// `*ELASTIC` under NLGEOM, i.e. St Venant-Kirchhoff (stress linear in Green strain): it
    /// softens in compression, so it bends more than neo-Hooke at large strain.
    StVenantKirchhoff,
    /// The body neo-Hookean, the DE stacks St Venant-Kirchhoff: the stacks' finite-strain law
    /// alone changed (what it does to the stacked scenes' growth with load).
    NeoHookeBodySvkStacks,
}

impl Law {
    pub fn name(self) -> &'static str {
        match self {
            Law::NeoHooke => "neo-Hookean",
            Law::StVenantKirchhoff => "St Venant-Kirchhoff",
            Law::NeoHookeBodySvkStacks => "neo-Hookean body, St Venant-Kirchhoff stacks",
        }
    }

    /// (body's law, stacks' law).
    fn parts(self) -> (Law, Law) {
        match self {
            Law::NeoHookeBodySvkStacks => (Law::NeoHooke, Law::StVenantKirchhoff),
            l => (l, l),
        }
    }
}

/// Gravity on the finger (docs/fidelity-fe.md "Under its own weight"): a body load of constant
/// magnitude and direction in the base frame, on every step of the run.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Gravity {
    /// Magnitude, m/s² (0: off).
    pub g_m_s2: f64,
    /// Direction in the base frame, degrees from the straight finger's axis (+x) toward the
    /// cable side (+y): 90 held horizontally curling downward with it, -90 curling upward
    /// against it, 0 hanging straight down, 180 pointing up.
    pub dir_deg: f64,
    /// The body's density, g/cm³.
    pub rho_body_g_cm3: f64,
    /// The stacks' (film's) density, g/cm³.
    pub rho_stack_g_cm3: f64,
}

impl Gravity {
    /// No gravity (the calibration's runs and every run before it).
    pub const OFF: Gravity = Gravity { g_m_s2: 0.0, dir_deg: 0.0, rho_body_g_cm3: 0.0, rho_stack_g_cm3: 0.0 };

    /// The gravity these parameters carry (`grav`, `grav_dir`, `rho_b`, the card's film
    /// density).
    pub fn of(p: &Params<f64>) -> Gravity {
        Gravity { g_m_s2: p.grav, dir_deg: p.grav_dir, rho_body_g_cm3: p.rho_b, rho_stack_g_cm3: p.card.rho_g_cm3 }
    }

    pub fn is_on(&self) -> bool {
        self.g_m_s2 != 0.0
    }
    /// The magnitude in the mesh's units, mm/s².
    pub fn mm_s2(&self) -> f64 {
        1e3 * self.g_m_s2
    }
    /// The unit direction (x, y) in the base frame.
    pub fn unit(&self) -> [f64; 2] {
        let (s, c) = self.dir_deg.to_radians().sin_cos();
        [c, s]
    }
}

/// g/cm³ to the mesh's units (mm, N, MPa: mass in tonnes), t/mm³.
pub fn t_per_mm3(g_cm3: f64) -> f64 {
    g_cm3 * 1e-9
}

/// A material card for (E, ν) in this law, with its density (t/mm³) if gravity is on.
fn material(s: &mut String, name: &str, e: f64, nu: f64, law: Law, rho_t_mm3: Option<f64>) {
    material_law(s, name, e, nu, law);
    if let Some(r) = rho_t_mm3 {
        let _ = writeln!(s, "*DENSITY\n{r:.9e}");
    }
}

fn material_law(s: &mut String, name: &str, e: f64, nu: f64, law: Law) {
    match law {
        Law::StVenantKirchhoff => {
            let _ = writeln!(s, "*MATERIAL, NAME={name}\n*ELASTIC\n{e:.9e}, {nu:.6}");
        }
        Law::NeoHooke | Law::NeoHookeBodySvkStacks => {
            let (g, k) = (e / (2.0 * (1.0 + nu)), e / (3.0 * (1.0 - 2.0 * nu)));
            let _ = writeln!(s, "*MATERIAL, NAME={name}\n*HYPERELASTIC, NEO HOOKE\n{:.9e}, {:.9e}", g / 2.0, 2.0 / k);
        }
    }
}

/// Nodal forces of one load case: (node, Fx, Fy), already for this model's share of the width.
pub type NodalLoads = Vec<(usize, f64, f64)>;

/// What a deck loads the mesh with.
pub enum Loads {
    /// The cable: constant-force springs between consecutive guide holes (node ids), NLGEOM, one
    /// step per tension (N), each ramped from the last.
    /// Gravity (`grav`) is applied in the first step, ramped with its tension, and held.
    Cable { holes: Vec<usize>, tensions: Vec<f64>, law: Law, grav: Gravity },
    /// Linear steps, one per load case.
    Unit(Vec<NodalLoads>),
}

/// An input deck and the node set whose displacements it prints.
pub struct Deck {
    pub text: String,
    pub out_nodes: Vec<usize>,
    /// Total step times at which each result is read (step ends).
    pub times: Vec<f64>,
}

/// Write the deck: mesh, materials (body E_b, nu_b; stack E_de, nu), the clamp x = `clamp_x`,
/// the symmetry plane (3D), loads, output.
pub fn deck(p: &Params<f64>, kind: Kind, mesh: &AnyMesh, clamp_x: f64, loads: &Loads, out_nodes: Vec<usize>) -> Deck {
    let mut s = String::new();
    let _ = writeln!(s, "*HEADING\nfinger-calculix: {}", kind.name());
    let _ = writeln!(s, "*NODE, NSET=NALL");
    for i in 0..mesh.node_count() {
        match mesh {
            AnyMesh::Two(m) => {
                let _ = writeln!(s, "{}, {:.12e}, {:.12e}", i + 1, m.nodes[i][0], m.nodes[i][1]);
            }
            AnyMesh::Three(m) => {
                let n = m.nodes[i];
                let _ = writeln!(s, "{}, {:.12e}, {:.12e}, {:.12e}", i + 1, n[0], n[1], n[2]);
            }
        }
    }
    let etype = match kind {
        Kind::PlaneStrain => "CPE8R",
        Kind::PlaneStress => "CPS8R",
        Kind::Half3d => "C3D20R",
    };
    // element blocks by (set, type); a collapsed quadrilateral (an edge of zero length, where a
    // stack ends) is written as a 6-node triangle in 2D: CalculiX's expansion of 2D elements
    // into bricks mishandles repeated nodes (the stack came out 7x too stiff); the 3D mesh's
    // own collapsed bricks are fine (they converge to the uncollapsed answer)
    let tri = match kind {
        Kind::PlaneStrain => "CPE6",
        _ => "CPS6",
    };
    let mut blocks: Vec<(String, &str, Material, Vec<Vec<usize>>)> = Vec::new();
    let mut push = |set: String, ty: &'static str, mat: Material, c: Vec<usize>| {
        if let Some(b) = blocks.iter_mut().find(|b| b.0 == set) {
            b.3.push(c);
        } else {
            blocks.push((set, ty, mat, vec![c]));
        }
    };
    match mesh {
        AnyMesh::Two(m) => {
            for (n, mat) in &m.elems {
                let base = if *mat == Material::Body { "EBODY" } else { "ESTACK" };
                if n[0] == n[3] {
                    push(format!("{base}T"), tri, *mat, vec![n[0], n[1], n[2], n[4], n[5], n[6]]);
                } else if n[1] == n[2] {
                    push(format!("{base}T"), tri, *mat, vec![n[0], n[1], n[3], n[4], n[6], n[7]]);
                } else {
                    push(base.to_string(), etype, *mat, n.to_vec());
                }
            }
        }
        AnyMesh::Three(m) => {
            for (n, mat) in &m.elems {
                let base = if *mat == Material::Body { "EBODY" } else { "ESTACK" };
                push(base.to_string(), etype, *mat, n.to_vec());
            }
        }
    }
    let mut next = 1usize;
    for (set, ty, _, conn) in &blocks {
        let _ = writeln!(s, "*ELEMENT, TYPE={ty}, ELSET={set}");
        for c in conn {
            // at most 16 entries per line; C3D20 continues on the next line
            let _ = write!(s, "{next}");
            for (i, id) in c.iter().enumerate() {
                if i == 15 {
                    let _ = write!(s, ",\n{}", id + 1);
                } else {
                    let _ = write!(s, ", {}", id + 1);
                }
            }
            let _ = writeln!(s);
            next += 1;
        }
    }
    let share = kind.load_share();
    match loads {
        Loads::Cable { holes, .. } => {
            for (set, pairs, _) in cable_springs(mesh, holes) {
                let _ = writeln!(s, "*ELEMENT, TYPE=SPRINGA, ELSET={set}");
                for (a, b) in pairs {
                    let _ = writeln!(s, "{next}, {}, {}", a + 1, b + 1);
                    next += 1;
                }
            }
        }
        Loads::Unit(_) => {}
    }
    let _ = writeln!(s, "*NSET, NSET=NCLAMP");
    for i in mesh.at_x(clamp_x) {
        let _ = writeln!(s, "{},", i + 1);
    }
    let _ = writeln!(s, "*NSET, NSET=NOUT");
    for &i in &out_nodes {
        let _ = writeln!(s, "{},", i + 1);
    }
    if let AnyMesh::Three(m) = mesh {
        let _ = writeln!(s, "*NSET, NSET=NSYM");
        for (i, n) in m.nodes.iter().enumerate() {
            if n[2].abs() < 1e-9 {
                let _ = writeln!(s, "{},", i + 1);
            }
        }
    }
    let law = match loads {
        Loads::Cable { law, .. } => *law,
        Loads::Unit(_) => Law::StVenantKirchhoff, // linear steps: Hooke's law
    };
    let grav = match loads {
        Loads::Cable { grav, .. } if grav.is_on() => Some(*grav),
        _ => None,
    };
    let (body_law, stack_law) = law.parts();
    material(&mut s, "BODY", p.e_b, p.nu_b, body_law, grav.map(|g| t_per_mm3(g.rho_body_g_cm3)));
    material(&mut s, "STACK", p.e_de(), p.nu, stack_law, grav.map(|g| t_per_mm3(g.rho_stack_g_cm3)));
    let thick = if kind == Kind::Half3d { String::new() } else { format!("\n{:.9e}", p.w) };
    for (set, _, mat, _) in &blocks {
        let name = if *mat == Material::Body { "BODY" } else { "STACK" };
        let _ = writeln!(s, "*SOLID SECTION, ELSET={set}, MATERIAL={name}{thick}");
    }
    let mut times = Vec::new();
    match loads {
        Loads::Cable { tensions, .. } => {
            // force = share x temperature: the step's temperature is the tension, ramped
            let tmax = 1000.0;
            if let Loads::Cable { holes, .. } = loads {
                for (set, _, frac) in cable_springs(mesh, holes) {
                    let _ = writeln!(
                        s,
                        "*SPRING, ELSET={set}, NONLINEAR\n0., -1.e4, 0.\n0., 1.e4, 0.\n{f:.9e}, -1.e4, {tmax:.1}\n{f:.9e}, 1.e4, {tmax:.1}",
                        f = share * frac * tmax
                    );
                }
            }
            let _ = writeln!(s, "*INITIAL CONDITIONS, TYPE=TEMPERATURE\nNALL, 0.");
            write_bcs(&mut s, mesh);
            for (i, t) in tensions.iter().enumerate() {
                let _ = writeln!(s, "*STEP, NLGEOM, INC=2000\n*STATIC\n0.25, 1., 1.e-6, 0.5\n*TEMPERATURE\nNALL, {t:.9e}");
                if let (0, Some(g)) = (i, grav) {
                    // the body load on the solid elements (not the cable's springs)
                    let u = g.unit();
                    let _ = writeln!(s, "*DLOAD");
                    for (set, _, _, _) in &blocks {
                        let _ = writeln!(s, "{set}, GRAV, {:.9e}, {:.12e}, {:.12e}, 0.", g.mm_s2(), u[0], u[1]);
                    }
                }
                let _ = writeln!(s, "*NODE PRINT, NSET=NOUT\nU\n*NODE PRINT, NSET=NCLAMP\nRF\n*END STEP");
                times.push((i + 1) as f64);
            }
        }
        Loads::Unit(cases) => {
            write_bcs(&mut s, mesh);
            for (i, c) in cases.iter().enumerate() {
                let _ = writeln!(s, "*STEP\n*STATIC\n*CLOAD, OP=NEW");
                for &(n, fx, fy) in c {
                    let _ = writeln!(s, "{}, 1, {fx:.12e}\n{}, 2, {fy:.12e}", n + 1, n + 1);
                }
                let _ = writeln!(s, "*NODE PRINT, NSET=NOUT\nU\n*END STEP");
                times.push((i + 1) as f64);
            }
        }
    }
    Deck { text: s, out_nodes, times }
}

/// The cable's springs between consecutive guide holes: (element set, node pairs, share of the
/// tension each spring carries). In 2D one spring per span. In 3D the guide spans the width: a
/// spring per node of the hole's line across the half width (z), each carrying the consistent
/// share of a uniform line load on the quadratic edges (end corners 1/6, inner corners 1/3,
/// midsides 2/3 of a layer), so the cable loads a line, not a single node.
fn cable_springs(mesh: &AnyMesh, holes: &[usize]) -> Vec<(String, Vec<(usize, usize)>, f64)> {
    match mesh {
        AnyMesh::Two(_) => vec![("ECABLE".into(), holes.windows(2).map(|w| (w[0], w[1])).collect(), 1.0)],
        AnyMesh::Three(m) => {
            let line = |h: usize| -> Vec<usize> {
                let n = m.nodes[h];
                let mut l: Vec<usize> = (0..m.nodes.len()).filter(|&i| (m.nodes[i][0] - n[0]).abs() < 1e-6 && (m.nodes[i][1] - n[1]).abs() < 1e-6).collect();
                l.sort_by(|&a, &b| m.nodes[a][2].total_cmp(&m.nodes[b][2]));
                l
            };
            let lines: Vec<Vec<usize>> = holes.iter().map(|&h| line(h)).collect();
            let nz = lines.iter().map(|l| l.len()).min().unwrap_or(1) - 1;
            let layers = (nz / 2).max(1) as f64;
            let mut sets: Vec<(String, Vec<(usize, usize)>, f64)> = vec![
                ("ECABLEE".into(), Vec::new(), 1.0 / 6.0 / layers),
                ("ECABLEC".into(), Vec::new(), 1.0 / 3.0 / layers),
                ("ECABLEM".into(), Vec::new(), 2.0 / 3.0 / layers),
            ];
            for w in lines.windows(2) {
                for iz in 0..=nz {
                    let set = if iz % 2 == 1 {
                        2
                    } else if iz == 0 || iz == nz {
                        0
                    } else {
                        1
                    };
                    sets[set].1.push((w[0][iz], w[1][iz]));
                }
            }
            sets.retain(|s| !s.1.is_empty());
            sets
        }
    }
}

fn write_bcs(s: &mut String, mesh: &AnyMesh) {
    match mesh {
        AnyMesh::Two(_) => {
            let _ = writeln!(s, "*BOUNDARY\nNCLAMP, 1, 2");
        }
        AnyMesh::Three(_) => {
            let _ = writeln!(s, "*BOUNDARY\nNCLAMP, 1, 3\nNSYM, 3, 3");
        }
    }
}

/// Displacements (ux, uy) of the deck's output nodes (0-based mesh ids) at each step end.
pub type Results = Vec<BTreeMap<usize, [f64; 2]>>;

static COUNTER: std::sync::atomic::AtomicUsize = std::sync::atomic::AtomicUsize::new(0);

/// Run ccx on the deck in a fresh scratch directory and read the step-end displacements.
pub fn run(deck: &Deck) -> Result<Results, FeError> {
    match run_partial(deck)? {
        (r, None) => Ok(r),
        (_, Some(e)) => Err(e),
    }
}

/// `run`, keeping the steps that ended before a failure: (their results, the failure).
pub fn run_partial(deck: &Deck) -> Result<(Results, Option<FeError>), FeError> {
    let (dat, failure) = run_dat(deck)?;
    steps_done(&dat, deck, "displacements", failure)
}

/// `run_partial` with the clamp's reaction forces (nodes of NCLAMP, (RF_x, RF_y), this model's
/// share of the width) at the same step ends: (displacements, reactions, the failure). A cable
/// deck prints them.
pub fn run_partial_reactions(deck: &Deck) -> Result<(Results, Results, Option<FeError>), FeError> {
    let (dat, failure) = run_dat(deck)?;
    let (u, failure) = steps_done(&dat, deck, "displacements", failure)?;
    let d = Deck { text: String::new(), out_nodes: Vec::new(), times: deck.times[..u.len()].to_vec() };
    let rf = parse_blocks(&dat, &d, "forces")?;
    Ok((u, rf, failure))
}

/// The steps' results read from a `.dat`: all of them, or after a failure the steps that ended
/// before it.
fn steps_done(dat: &str, deck: &Deck, what: &str, failure: Option<FeError>) -> Result<(Results, Option<FeError>), FeError> {
    match failure {
        None => Ok((parse_blocks(dat, deck, what)?, None)),
        Some(e) => {
            let mut done = Vec::new();
            for k in 1..=deck.times.len() {
                let d = Deck { text: String::new(), out_nodes: deck.out_nodes.clone(), times: deck.times[..k].to_vec() };
                match parse_blocks(dat, &d, what) {
                    Ok(r) => done = r,
                    Err(_) => break,
                }
            }
            Ok((done, Some(e)))
        }
    }
}

static CACHE: std::sync::Mutex<Option<PathBuf>> = std::sync::Mutex::new(None);

/// Keep every successful run's `.dat` in `dir` by its deck (a hash of the deck's text and its
/// length), and read it from there when the same deck runs again (ccx is deterministic on one
/// thread): the report's runs, so that rerunning the report after a model change does not solve
/// the FE again. None (the default, and the tests'): every deck is solved.
pub fn set_cache(dir: Option<PathBuf>) {
    *CACHE.lock().unwrap_or_else(|e| e.into_inner()) = dir;
}

fn cache_file(deck: &Deck) -> Option<PathBuf> {
    let dir = CACHE.lock().unwrap_or_else(|e| e.into_inner()).clone()?;
    // FNV-1a, 64 bits
    let h = deck.text.bytes().fold(0xcbf2_9ce4_8422_2325u64, |h, b| (h ^ b as u64).wrapping_mul(0x0000_0100_0000_01b3));
    Some(dir.join(format!("{h:016x}-{}.dat", deck.text.len())))
}

/// Run ccx on the deck in a fresh scratch directory (or read its kept `.dat`, `set_cache`):
/// (the `.dat`, the failure if it failed).
fn run_dat(deck: &Deck) -> Result<(String, Option<FeError>), FeError> {
    let cached = cache_file(deck);
    if let Some(dat) = cached.as_ref().and_then(|f| std::fs::read_to_string(f).ok()) {
        // its CPU time beside it
        let cpu = cached.as_ref().and_then(|f| std::fs::read_to_string(f.with_extension("cpu")).ok()).and_then(|s| s.trim().parse::<f64>().ok()).unwrap_or(0.0);
        CPU_S.with(|c| c.set(c.get() + cpu));
        return Ok((dat, None));
    }
    let (dat, failure, cpu) = run_ccx(deck)?;
    CPU_S.with(|c| c.set(c.get() + cpu));
    if let (Some(f), None) = (&cached, &failure) {
        let _ = std::fs::create_dir_all(f.parent().unwrap_or(f))
            .and_then(|_| std::fs::write(f.with_extension("cpu"), format!("{cpu}\n")))
            .and_then(|_| std::fs::write(f, &dat));
    }
    Ok((dat, failure))
}

thread_local! {
    static CPU_S: std::cell::Cell<f64> = const { std::cell::Cell::new(0.0) };
}

/// The CPU time (user + system, s) of the ccx runs this thread has made so far, a kept run
/// counting what it took when it was solved (Linux; 0 where /proc is not there).
pub fn thread_cpu_seconds() -> f64 {
    CPU_S.with(|c| c.get())
}

/// A child's CPU time (s) once it has exited and before it is reaped: fields 14 and 15 of
/// /proc/<pid>/stat (clock ticks of 1/100 s, Linux's USER_HZ). None while it runs.
fn exited_cpu_s(pid: u32) -> Option<Option<f64>> {
    let Ok(stat) = std::fs::read_to_string(format!("/proc/{pid}/stat")) else { return Some(None) };
    let f: Vec<&str> = stat.rsplit_once(')').map_or("", |x| x.1).split_whitespace().collect();
    match f.first() {
        Some(&"Z") | Some(&"X") => Some(f.get(11).zip(f.get(12)).and_then(|(u, s)| Some((u.parse::<f64>().ok()? + s.parse::<f64>().ok()?) / 100.0))),
        Some(_) => None,
        None => Some(None),
    }
}

fn run_ccx(deck: &Deck) -> Result<(String, Option<FeError>, f64), FeError> {
    let n = COUNTER.fetch_add(1, std::sync::atomic::Ordering::SeqCst);
    let dir: PathBuf = std::env::temp_dir().join(format!("finger-calculix-{}-{n}", std::process::id()));
    std::fs::create_dir_all(&dir).map_err(|e| FeError::Spawn(e.to_string()))?;
    std::fs::write(dir.join("job.inp"), &deck.text).map_err(|e| FeError::Spawn(e.to_string()))?;
    let file = |name: &str| std::fs::File::create(dir.join(name)).map_err(|e| FeError::Spawn(e.to_string()));
    let mut child = Command::new("ccx")
        .arg("-i")
        .arg("job")
        .current_dir(&dir)
        .env("OMP_NUM_THREADS", "1")
        .env("CCX_NPROC_EQUATION_SOLVER", "1")
        .stdout(file("log.out")?)
        .stderr(file("log.err")?)
        .spawn()
        .map_err(|e| FeError::Spawn(e.to_string()))?;
    // wait for it to exit, read its CPU time, then reap it
    let mut nap = std::time::Duration::from_millis(1);
    let cpu = loop {
        if let Some(c) = exited_cpu_s(child.id()) {
            break c.unwrap_or(0.0);
        }
        std::thread::sleep(nap);
        nap = (nap * 2).min(std::time::Duration::from_millis(20));
    };
    let status = child.wait().map_err(|e| FeError::Spawn(e.to_string()))?;
    let read = |name: &str| std::fs::read(dir.join(name)).map(|b| String::from_utf8_lossy(&b).into_owned()).unwrap_or_default();
    let log = read("log.out") + &read("log.err");
    let dat = read("job.dat");
    let keep = std::env::var_os("FINGER_CALCULIX_KEEP").is_some();
    if !keep {
        let _ = std::fs::remove_dir_all(&dir);
    }
    if !status.success() || log.contains("*ERROR") {
        let tail: Vec<&str> = log.lines().filter(|l| !l.trim().is_empty()).collect();
        let tail = tail[tail.len().saturating_sub(6)..].join(" | ");
        return Ok((dat, Some(FeError::Ccx(tail)), cpu));
    }
    Ok((dat, None, cpu))
}

/// The `.dat` blocks "displacements (vx,vy,vz) for set NOUT and time T", at the step ends.
pub fn parse_dat(dat: &str, deck: &Deck) -> Result<Results, FeError> {
    parse_blocks(dat, deck, "displacements")
}

/// The `.dat` blocks whose header starts with `what` ("displacements", "forces"), at the step
/// ends; for "displacements" every output node must be there.
fn parse_blocks(dat: &str, deck: &Deck, what: &str) -> Result<Results, FeError> {
    let mut blocks: Vec<(f64, BTreeMap<usize, [f64; 2]>)> = Vec::new();
    let mut cur: Option<(f64, BTreeMap<usize, [f64; 2]>)> = None;
    for line in dat.lines() {
        let l = line.trim();
        if l.starts_with(what) {
            if let Some(b) = cur.take() {
                blocks.push(b);
            }
            let t: f64 = l.rsplit(' ').next().and_then(|v| v.parse().ok()).ok_or_else(|| FeError::Parse(format!("time in '{l}'")))?;
            cur = Some((t, BTreeMap::new()));
        } else if let Some((_, map)) = cur.as_mut() {
            let f: Vec<&str> = l.split_whitespace().collect();
            if f.len() == 4 {
                if let (Ok(id), Ok(ux), Ok(uy)) = (f[0].parse::<usize>(), f[1].parse::<f64>(), f[2].parse::<f64>()) {
                    map.insert(id - 1, [ux, uy]);
                    continue;
                }
            }
            if !l.is_empty() {
                if let Some(b) = cur.take() {
                    blocks.push(b);
                }
            }
        }
    }
    if let Some(b) = cur.take() {
        blocks.push(b);
    }
    let mut out = Vec::new();
    for &t in &deck.times {
        let b = blocks
            .iter()
            .rev()
            .find(|b| (b.0 - t).abs() < 1e-6 * t.max(1.0))
            .ok_or_else(|| FeError::Parse(format!("no {what} at step end t = {t} (did the step converge?)")))?;
        if deck.out_nodes.iter().any(|n| !b.1.contains_key(n)) {
            return Err(FeError::Parse(format!("missing output nodes at t = {t}")));
        }
        out.push(b.1.clone());
    }
    Ok(out)
}
