//! The fixed scene set of the performance report, a dependency of the bench images (target)
//! and of perf-report (host reference).
//!
//! docs/model.md's finger (3 joints, corrected DE modulus) in the paper's model, pinned here (one
//! compliance per hinge, m = 1, the body modulus, rigid links) so that the report does not move
//! with the library's defaults; two scenes (`-fid`) use the fidelity model (m = 8 sub-elements,
//! plate modulus, flexible links) to show its cost. With (`layers` = 4) and without
//! (`layers` = 0) DE stacks. Loads are the paper's 0.2, 0.5 and 1.0 N, uniform and per-joint
//! voltages, and two high tensions: 7 N (where the paper's stepping at n_inc = 1 is off by
//! tens of mm) and 250 N (near contact: the links touch at about 300 N).
#![no_std]

/// One scene: cable tension (N), DE layers per stack, channel voltages (V).
#[derive(Clone, Copy, Debug)]
pub struct Scene {
    pub name: &'static str,
    pub layers: u32,
    pub tension: f64,
    pub volts: [f64; 3],
    /// The fidelity model (m = 8, plate modulus, flexible links) instead of the paper's.
    pub fidelity: bool,
    /// Under standard gravity along this direction (degrees, docs/model.md "Gravity"), or none.
    pub gravity: Option<f64>,
}

const fn sc(name: &'static str, layers: u32, tension: f64, volts: [f64; 3]) -> Scene {
    Scene { name, layers, tension, volts, fidelity: false, gravity: None }
}

const fn fid(name: &'static str, layers: u32, tension: f64, volts: [f64; 3]) -> Scene {
    Scene { name, layers, tension, volts, fidelity: true, gravity: None }
}

/// A fidelity-model scene under gravity along `dir` degrees.
const fn fid_grav(name: &'static str, layers: u32, tension: f64, volts: [f64; 3], dir: f64) -> Scene {
    Scene { name, layers, tension, volts, fidelity: true, gravity: Some(dir) }
}

/// The scene's parameters: docs/model.md's values with the hinge model pinned (and gravity, if
/// the scene has it).
pub fn params(s: &Scene) -> finger_model::Params<f64> {
    let (m, plate, flex_links) = if s.fidelity { (8, true, true) } else { (1, false, false) };
    let p = finger_model::Params { layers: s.layers, m, plate, flex_links, ..finger_model::Params::default() };
    match s.gravity {
        Some(dir) => p.with_gravity(finger_model::params::G_STANDARD, dir),
        None => p,
    }
}

pub const SCENES: &[Scene] = &[
    sc("bare-0.2N", 0, 0.2, [0.0; 3]),
    sc("bare-0.5N", 0, 0.5, [0.0; 3]),
    sc("bare-1.0N", 0, 1.0, [0.0; 3]),
    sc("de-0.2N", 4, 0.2, [0.0; 3]),
    sc("de-0.5N", 4, 0.5, [0.0; 3]),
    sc("de-1.0N", 4, 1.0, [0.0; 3]),
    sc("de-1.0N-uni8kV", 4, 1.0, [8000.0; 3]),
    sc("de-1.0N-per9/5/0kV", 4, 1.0, [9000.0, 5000.0, 0.0]),
    sc("bare-7N", 0, 7.0, [0.0; 3]),
    sc("bare-250N-contact", 0, 250.0, [0.0; 3]),
    fid("bare-1.0N-fid", 0, 1.0, [0.0; 3]),
    fid("de-1.0N-per9/5/0kV-fid", 4, 1.0, [9000.0, 5000.0, 0.0]),
    fid_grav("de-1.0N-per9/5/0kV-fid-g0", 4, 1.0, [9000.0, 5000.0, 0.0], 0.0),
    fid_grav("de-1.0N-per9/5/0kV-fid-g90", 4, 1.0, [9000.0, 5000.0, 0.0], 90.0),
];

/// The paper's stepping at these increment counts; plus the converged solver.
pub const N_INC: &[u32] = &[1, 2, 5, 10, 20, 50, 100, 200];

/// The branch-table path (`inverse::BranchTable`): the models it is measured on,
/// and the scenes (tension N, channel voltages V). Every model has stacks (the table
/// tabulates the stack's thickness range).
#[derive(Clone, Copy, Debug)]
pub struct TableModel {
    pub name: &'static str,
    /// m = 8, plate modulus, flexible links (docs/model.md's defaults) if true, else the paper's
    /// m = 1, body modulus, rigid links.
    pub fidelity: bool,
    /// docs/model.md's FE calibration factors (docs/fidelity-fe.md) applied.
    pub calibrated: bool,
}

pub const TABLE_MODELS: &[TableModel] = &[
    TableModel { name: "m8-default", fidelity: true, calibrated: false },
    TableModel { name: "m8-calibrated", fidelity: true, calibrated: true },
    TableModel { name: "m1-paper", fidelity: false, calibrated: false },
];

/// (name, tension N, voltages V): the bench scenes with stacks, and two higher tensions below
/// the default model's branch end (about 18 N).
pub const TABLE_SCENES: &[(&str, f64, [f64; 3])] = &[
    ("de-0.2N", 0.2, [0.0; 3]),
    ("de-0.5N", 0.5, [0.0; 3]),
    ("de-1.0N", 1.0, [0.0; 3]),
    ("de-1.0N-uni8kV", 1.0, [8000.0; 3]),
    ("de-1.0N-per9/5/0kV", 1.0, [9000.0, 5000.0, 0.0]),
    ("de-7N", 7.0, [0.0; 3]),
    ("de-7N-per9/5/0kV", 7.0, [9000.0, 5000.0, 0.0]),
    ("de-15N-per2/6/9kV", 15.0, [2000.0, 6000.0, 9000.0]),
];

/// A table model's parameters (4 layers per stack) and calibration factors (hinge x4,
/// stack EA g0 g1, stack EI g0 g1; all 1 and 0 when uncalibrated).
pub fn table_params(m: &TableModel) -> (finger_model::Params<f64>, [f64; 8]) {
    let (mm, plate, flex_links) = if m.fidelity { (8, true, true) } else { (1, false, false) };
    let p = finger_model::Params { layers: 4, m: mm, plate, flex_links, ..finger_model::Params::default() };
    let cal = if m.calibrated { [1.5407, 6.2456, 1.0669, 1.1546, 0.7183, 0.0546, 5.2540, -1.7563] } else { [1.0, 1.0, 1.0, 1.0, 1.0, 0.0, 1.0, 0.0] };
    (p, cal)
}
