//! finger-calculix: the finger in a real finite-element solver (CalculiX `ccx`), to measure the
//! model against and to calibrate it (docs/fidelity-fe.md, docs/model.md "FE calibration").
//!
//! - [`mesh`]: the plane mesh from `Params` (notches, links, stacks) and its 3D extrusion.
//! - [`ccx`]: the input deck, running ccx, reading its `.dat`.
//! - this file: the finger under cable tension and gravity (NLGEOM, follower springs, a
//!   `GRAV` body load), the clamp's reaction, section poses,
//!   joint angles and tip; one element's small-load compliance (linear unit loads).
//! - [`gravity`]: the finger under its own weight in three orientations, model against FE.
//! - [`calibrate`]: corrections to the model's sub-element compliances from those unit loads.
//! - [`em`]: the electromechanical FE: the voltage applied to the stacks (the Maxwell stress at
//!   each layer's current thickness, to a fixed point), not the model's thicknesses (`fe-em`).
//!
//! Definitions (the same in the report):
//! - a section's pose: the least-squares rigid motion of its nodes (position of its centre,
//!   angle of the best-fit line through its displaced nodes);
//! - node k: the section x = k l (where link k ends and hinge k+1 begins; node 0 the clamp);
//! - joint angle k: section k's angle minus section k-1's, the model's node-to-node angle;
//! - tip: section n (the finger's end face).

pub mod calibrate;
pub mod gravity;
pub mod ccx;
pub mod em;
pub mod mesh;

pub use ccx::Gravity;
use ccx::{AnyMesh, FeError, Kind, Law, Loads, NodalLoads};
use finger_model::mat3::Mat3;
use finger_model::Params;
use mesh::{Density, Segment};
use std::collections::BTreeMap;
use std::fmt::Write as _;

/// Sets `name=value` overrides on `p` (a command line's parameters), all at once
/// (`Params::set_many`: each in its range, then the set, so their order does not matter).
pub fn apply_overrides(p: &mut Params<f64>, sets: Vec<(String, f64)>) -> Result<(), String> {
    let named: Vec<(&str, f64)> = sets.iter().map(|(k, v)| (k.as_str(), *v)).collect();
    p.set_many(&named).map_err(|e| {
        let listed = sets.iter().map(|(k, v)| format!("{k}={v}")).collect::<Vec<_>>().join(" ");
        format!("{listed}: {e}")
    })
}

/// A section's rigid motion: centre position (mm, base frame) and angle (rad).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SectionPose {
    pub x: f64,
    pub y: f64,
    pub theta: f64,
}

/// Least-squares rigid motion of a section's nodes (2D Procrustes about the reference centre
/// (x0, 0)): `theta = atan2(-Σ r_y d_x, Σ r_y d_y)`, r the reference offsets from their mean and
/// d the displaced ones.
pub fn section_pose(mesh: &AnyMesh, nodes: &[usize], u: &BTreeMap<usize, [f64; 2]>) -> SectionPose {
    let n = nodes.len() as f64;
    let (mut rx, mut ry, mut px, mut py) = (0.0, 0.0, 0.0, 0.0);
    for &i in nodes {
        let r = mesh.xy(i);
        let d = u[&i];
        rx += r[0];
        ry += r[1];
        px += r[0] + d[0];
        py += r[1] + d[1];
    }
    let (rx, ry, px, py) = (rx / n, ry / n, px / n, py / n);
    let (mut sn, mut cs) = (0.0, 0.0);
    for &i in nodes {
        let r = mesh.xy(i);
        let d = u[&i];
        let (ax, ay) = (r[0] - rx, r[1] - ry);
        let (bx, by) = (r[0] + d[0] - px, r[1] + d[1] - py);
        sn += ax * by - ay * bx;
        cs += ax * bx + ay * by;
    }
    let theta = sn.atan2(cs);
    // the centre (rx, 0) on the section's line: the mean moved by R(theta) of its offset
    // from the mean, (0, -ry)
    let (s, c) = theta.sin_cos();
    let (ox, oy) = (0.0, -ry);
    SectionPose { x: px + c * ox - s * oy, y: py + s * ox + c * oy, theta }
}

/// The finger under one cable tension.
#[derive(Clone, Debug)]
pub struct FeState {
    pub tension: f64,
    /// Sections 0..=n.
    pub nodes: Vec<SectionPose>,
    /// Joint angles, rad (section k minus section k-1).
    pub joint_angle: Vec<f64>,
    /// Cable span k (hole at node k-1 to link k's proximal hole), mm.
    pub span: Vec<f64>,
    /// The clamp's reaction on the finger, whole width: (Fx N, Fy N, M N·mm about the clamp
    /// section's centre (0, 0)).
    pub root: [f64; 3],
}

impl FeState {
    pub fn tip(&self) -> SectionPose {
        *self.nodes.last().unwrap()
    }
}

/// The whole finger's mesh for these stack thicknesses (mm per joint, 0: none).
pub fn finger_mesh(p: &Params<f64>, stack_mm: &[f64], kind: Kind, d: &Density) -> AnyMesh {
    let m2 = mesh::mesh2(p, &mesh::finger_segments(p, stack_mm), d);
    match kind {
        Kind::Half3d => AnyMesh::Three(mesh::extrude(&m2, p.w / 2.0, d.layers)),
        _ => AnyMesh::Two(m2),
    }
}

/// The finger clamped at x = 0, pulled by the cable (constant tension through every guide hole,
/// anchored at the tip), NLGEOM: one ccx run, one state per tension (increasing).
pub fn finger_under_cable(p: &Params<f64>, stack_mm: &[f64], kind: Kind, d: &Density, law: Law, tensions: &[f64]) -> Result<Vec<FeState>, FeError> {
    finger_under_load(p, stack_mm, kind, d, law, &Gravity::OFF, tensions)
}

/// `finger_under_cable` under gravity too (applied with the first tension and held).
pub fn finger_under_load(
    p: &Params<f64>,
    stack_mm: &[f64],
    kind: Kind,
    d: &Density,
    law: Law,
    grav: &Gravity,
    tensions: &[f64],
) -> Result<Vec<FeState>, FeError> {
    match finger_under_load_partial(p, stack_mm, kind, d, law, grav, tensions)? {
        (s, None) => Ok(s),
        (_, Some(e)) => Err(e),
    }
}

/// `finger_under_cable`, keeping the tensions solved before ccx stopped: (states, why it stopped).
pub fn finger_under_cable_partial(
    p: &Params<f64>,
    stack_mm: &[f64],
    kind: Kind,
    d: &Density,
    law: Law,
    tensions: &[f64],
) -> Result<(Vec<FeState>, Option<FeError>), FeError> {
    finger_under_load_partial(p, stack_mm, kind, d, law, &Gravity::OFF, tensions)
}

/// The clamp's reaction (Fx, Fy, M about (0, 0)) on the finger from its nodes' reaction forces
/// (this model's share), for the whole width.
fn root_reaction(mesh: &AnyMesh, kind: Kind, rf: &BTreeMap<usize, [f64; 2]>) -> [f64; 3] {
    let mut r = [0.0; 3];
    for (&i, f) in rf {
        let x = mesh.xy(i);
        r[0] += f[0];
        r[1] += f[1];
        r[2] += x[0] * f[1] - x[1] * f[0];
    }
    r.map(|v| v / kind.load_share())
}

/// `finger_under_load`, keeping the tensions solved before ccx stopped: (states, why it stopped).
pub fn finger_under_load_partial(
    p: &Params<f64>,
    stack_mm: &[f64],
    kind: Kind,
    d: &Density,
    law: Law,
    grav: &Gravity,
    tensions: &[f64],
) -> Result<(Vec<FeState>, Option<FeError>), FeError> {
    let mesh = finger_mesh(p, stack_mm, kind, d);
    // guide holes: base (node 0), then per link its proximal end and node k
    let mut holes = vec![mesh.find(0.0, p.e)?];
    for k in 0..p.n {
        let x0 = k as f64 * p.l;
        holes.push(mesh.find(x0 + 2.0 * p.a, p.e)?);
        holes.push(mesh.find(x0 + p.l, p.e)?);
    }
    let sections: Vec<Vec<usize>> = (0..=p.n).map(|k| mesh.at_x(k as f64 * p.l)).collect();
    let mut out_nodes: Vec<usize> = sections.iter().flatten().copied().chain(holes.iter().copied()).collect();
    out_nodes.sort();
    out_nodes.dedup();
    let loads = Loads::Cable { holes: holes.clone(), tensions: tensions.to_vec(), law, grav: *grav };
    let deck = ccx::deck(p, kind, &mesh, 0.0, &loads, out_nodes);
    let (res, rf, failure) = ccx::run_partial_reactions(&deck)?;
    let mut states = Vec::new();
    for ((t, u), rf) in tensions.iter().zip(res.iter()).zip(rf.iter()) {
        let mut nodes: Vec<SectionPose> = sections.iter().map(|s| section_pose(&mesh, s, u)).collect();
        // unwrap along the finger: each joint turns by less than half a turn
        for k in 1..nodes.len() {
            let d = nodes[k].theta - nodes[k - 1].theta;
            let d = d - (2.0 * std::f64::consts::PI) * (d / (2.0 * std::f64::consts::PI)).round();
            nodes[k].theta = nodes[k - 1].theta + d;
        }
        let joint_angle = (1..=p.n).map(|k| nodes[k].theta - nodes[k - 1].theta).collect();
        let pos = |i: usize| {
            let r = mesh.xy(i);
            [r[0] + u[&i][0], r[1] + u[&i][1]]
        };
        let span = (0..p.n)
            .map(|k| {
                let (a, b) = (pos(holes[2 * k]), pos(holes[2 * k + 1]));
                ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
            })
            .collect();
        states.push(FeState { tension: *t, nodes, joint_angle, span, root: root_reaction(&mesh, kind, rf) });
    }
    Ok((states, failure))
}

/// Length of the link stubs around the calibration element (mm): one link thickness, so the
/// clamp and the loaded face are a thickness away from the sections measured.
pub fn stub_len(p: &Params<f64>) -> f64 {
    p.b
}

/// One element's small-load compliance (linear FE): hinge (with a stack of `stack_mm`) and
/// link between sections x = 0 and x = l, with link stubs before (clamped) and after (loaded
/// at its end face); the displacement of section l relative to section 0 (in its frame) per
/// unit wrench at section l (Fx, Fy, M about its centre), as the model's element compliance.
pub fn element_compliance(p: &Params<f64>, stack_mm: f64, kind: Kind, d: &Density) -> Result<Mat3<f64>, FeError> {
    let s = stub_len(p);
    let segs = [
        Segment::Link { x0: -s, x1: 0.0 },
        Segment::Notch { x0: 0.0, stack_mm },
        Segment::Link { x0: 2.0 * p.a, x1: p.l },
        Segment::Link { x0: p.l, x1: p.l + s },
    ];
    compliance_between(p, &segs, kind, d, 0.0, p.l)
}

/// A uniform strip of thickness p.b and length `len`, clamped at x = 0 (loaded at the end of a
/// stub of one thickness past x = len): the compliance of section `len` (beam-theory checks).
pub fn beam_compliance(p: &Params<f64>, len: f64, kind: Kind, d: &Density) -> Result<Mat3<f64>, FeError> {
    let segs = [Segment::Link { x0: 0.0, x1: len }, Segment::Link { x0: len, x1: len + p.b }];
    compliance_between(p, &segs, kind, d, 0.0, len)
}

/// Linear unit loads on the last segment's end face (the mesh is clamped at its first
/// segment's start): section `xb`'s displacement relative to section `xa`'s rigid motion, per
/// unit wrench at section `xb` (moment about its centre). `C = Δ W⁻¹` over three load cases.
pub fn compliance_between(p: &Params<f64>, segs: &[Segment], kind: Kind, d: &Density, xa: f64, xb: f64) -> Result<Mat3<f64>, FeError> {
    let x_clamp = match segs[0] {
        Segment::Link { x0, .. } | Segment::Notch { x0, .. } => x0,
    };
    let x_face = match *segs.last().unwrap() {
        Segment::Link { x1, .. } => x1,
        Segment::Notch { x0, .. } => x0 + 2.0 * p.a,
    };
    let m2 = mesh::mesh2(p, segs, d);
    let mesh = match kind {
        Kind::Half3d => AnyMesh::Three(mesh::extrude(&m2, p.w / 2.0, d.layers)),
        _ => AnyMesh::Two(m2),
    };
    let (sa, sb) = (mesh.at_x(xa), mesh.at_x(xb));
    if sa.is_empty() || sb.is_empty() {
        return Err(FeError::Mesh(format!("no section at x = {xa} or {xb}")));
    }
    let mut out: Vec<usize> = sa.iter().chain(sb.iter()).copied().collect();
    out.sort();
    out.dedup();
    // small loads: the section fit measures finite rotations (atan of the linear field's
    // slope), so the linear solution is read where atan(θ) = θ to 1e-6
    let f = 1e-3;
    let cases = [[f, 0.0, 0.0], [0.0, f, 0.0], [0.0, 0.0, f]];
    let arm = x_face - xb;
    let loads = Loads::Unit(cases.iter().map(|c| face_loads(p, kind, &mesh, x_face, *c)).collect::<Result<_, _>>()?);
    let deck = ccx::deck(p, kind, &mesh, x_clamp, &loads, out);
    let res = ccx::run(&deck)?;
    let mut delta = [[0.0; 3]; 3]; // columns: cases
    let mut wrench = [[0.0; 3]; 3];
    for (j, (c, u)) in cases.iter().zip(res.iter()).enumerate() {
        let a = section_pose(&mesh, &sa, u);
        let b = section_pose(&mesh, &sb, u);
        let (ua, ub) = ([a.x - xa, a.y, a.theta], [b.x - xb, b.y, b.theta]);
        let l = xb - xa;
        let rel = [ub[0] - ua[0], ub[1] - ua[1] - l * ua[2], ub[2] - ua[2]];
        let w = [c[0], c[1], c[2] + arm * c[1]];
        for i in 0..3 {
            delta[i][j] = rel[i];
            wrench[i][j] = w[i];
        }
    }
    let winv = finger_model::mat3::inverse(&wrench).ok_or_else(|| FeError::Parse("singular load cases".into()))?;
    Ok(finger_model::mat3::mul(&delta, &winv))
}

/// Consistent nodal forces on the end face x = `xf` of a strip of thickness b for the wrench
/// (Fx, Fy, M about (xf, 0)), whole-width values: Fx uniform, Fy parabolic (6 F/b³ (b²/4 - y²)),
/// M linear (σ = -12 M y / b³), each ∫ N_i q over the face's quadratic edges (2D) or 8-node
/// faces (3D), 3-point Gauss.
pub fn face_loads(p: &Params<f64>, kind: Kind, mesh: &AnyMesh, xf: f64, w: [f64; 3]) -> Result<NodalLoads, FeError> {
    let b = p.b;
    let share = kind.load_share();
    let depth = if kind == Kind::Half3d { p.w / 2.0 } else { 1.0 };
    // traction per unit face area (per unit y in 2D), x and y components
    let q = |y: f64| -> [f64; 2] {
        let c = share / depth;
        [c * (w[0] / b - 12.0 * w[2] * y / (b * b * b)), c * 6.0 * w[1] / (b * b * b) * (b * b / 4.0 - y * y)]
    };
    let mut ys: Vec<f64> = mesh.at_x(xf).iter().map(|&i| mesh.xy(i)[1]).collect();
    ys.sort_by(f64::total_cmp);
    ys.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
    if ys.len() < 3 || ys.len().is_multiple_of(2) {
        return Err(FeError::Mesh(format!("face x = {xf}: {} node rows", ys.len())));
    }
    let g = [(-(0.6f64).sqrt(), 5.0 / 9.0), (0.0, 8.0 / 9.0), ((0.6f64).sqrt(), 5.0 / 9.0)];
    let n1 = |x: f64| [x * (x - 1.0) / 2.0, 1.0 - x * x, x * (x + 1.0) / 2.0];
    let mut f: BTreeMap<usize, [f64; 2]> = BTreeMap::new();
    let mut add = |i: usize, v: [f64; 2], s: f64| {
        let e = f.entry(i).or_insert([0.0; 2]);
        e[0] += v[0] * s;
        e[1] += v[1] * s;
    };
    for e in (0..ys.len() - 1).step_by(2) {
        let (y0, y2) = (ys[e], ys[e + 2]);
        let jy = (y2 - y0) / 2.0;
        match mesh {
            AnyMesh::Two(_) => {
                let ids = [mesh.find(xf, ys[e])?, mesh.find(xf, ys[e + 1])?, mesh.find(xf, ys[e + 2])?];
                for &(xi, wt) in &g {
                    let y = y0 + (xi + 1.0) * jy;
                    let n = n1(xi);
                    for k in 0..3 {
                        add(ids[k], q(y), n[k] * wt * jy);
                    }
                }
            }
            AnyMesh::Three(m3) => {
                let mut zs: Vec<f64> = mesh.at_x(xf).iter().map(|&i| m3.nodes[i][2]).collect();
                zs.sort_by(f64::total_cmp);
                zs.dedup_by(|a, b| (*a - *b).abs() < 1e-9);
                for l in (0..zs.len() - 1).step_by(2) {
                    let (z0, z1) = (zs[l], zs[l + 2]);
                    let jz = (z1 - z0) / 2.0;
                    let at = |y: f64, z: f64| m3.find(xf, y, z).ok_or_else(|| FeError::Mesh(format!("face node ({xf}, {y}, {z})")));
                    // serendipity face: corners (±1, ±1), midsides
                    let pts: [(f64, f64, usize); 8] = [
                        (-1.0, -1.0, at(y0, z0)?),
                        (1.0, -1.0, at(y2, z0)?),
                        (1.0, 1.0, at(y2, z1)?),
                        (-1.0, 1.0, at(y0, z1)?),
                        (0.0, -1.0, at(ys[e + 1], z0)?),
                        (1.0, 0.0, at(y2, zs[l + 1])?),
                        (0.0, 1.0, at(ys[e + 1], z1)?),
                        (-1.0, 0.0, at(y0, zs[l + 1])?),
                    ];
                    for &(xi, wx) in &g {
                        for &(et, wz) in &g {
                            let y = y0 + (xi + 1.0) * jy;
                            for &(a, c, id) in &pts {
                                let n = if a != 0.0 && c != 0.0 {
                                    (1.0 + xi * a) * (1.0 + et * c) * (xi * a + et * c - 1.0) / 4.0
                                } else if a == 0.0 {
                                    (1.0 - xi * xi) * (1.0 + et * c) / 2.0
                                } else {
                                    (1.0 + xi * a) * (1.0 - et * et) / 2.0
                                };
                                add(id, q(y), n * wx * wz * jy * jz);
                            }
                        }
                    }
                }
            }
        }
    }
    Ok(f.into_iter().map(|(i, v)| (i, v[0], v[1])).collect())
}

/// The finger under one cable tension and its tip stiffness there: the NLGEOM cable step, then
/// three steps each adding one small tip load to it (Fx, Fy, a moment M, `perturb` = (N, N,
/// N·mm), whole width) on the end face; the tip's motion per load is a column of the tip
/// compliance in the base frame (x mm, y mm, θ rad per Fx N, Fy N, M N·mm), as the model's
/// `Finger::tip_compliance`. The cable's springs keep their tension through the load steps,
/// so the FE's compliance includes the cable's geometric stiffness, which the model's does
/// not (docs/model.md "Tip stiffness").
pub fn tip_compliance_under_cable(
    p: &Params<f64>,
    stack_mm: &[f64],
    kind: Kind,
    d: &Density,
    law: Law,
    tension: f64,
    perturb: [f64; 3],
) -> Result<(FeState, Mat3<f64>), FeError> {
    let mesh = finger_mesh(p, stack_mm, kind, d);
    let mut holes = vec![mesh.find(0.0, p.e)?];
    for k in 0..p.n {
        let x0 = k as f64 * p.l;
        holes.push(mesh.find(x0 + 2.0 * p.a, p.e)?);
        holes.push(mesh.find(x0 + p.l, p.e)?);
    }
    let x_tip = p.n as f64 * p.l;
    let sections: Vec<Vec<usize>> = (0..=p.n).map(|k| mesh.at_x(k as f64 * p.l)).collect();
    let mut out_nodes: Vec<usize> = sections.iter().flatten().copied().chain(holes.iter().copied()).collect();
    out_nodes.sort();
    out_nodes.dedup();
    let loads = Loads::Cable { holes: holes.clone(), tensions: vec![tension], law, grav: Gravity::OFF };
    let mut deck = ccx::deck(p, kind, &mesh, 0.0, &loads, out_nodes);
    for (j, f) in perturb.iter().enumerate() {
        let mut w = [0.0; 3];
        w[j] = *f;
        let _ = writeln!(deck.text, "*STEP, NLGEOM, INC=2000\n*STATIC\n0.5, 1., 1.e-6, 1.\n*CLOAD, OP=NEW");
        for (n, fx, fy) in face_loads(p, kind, &mesh, x_tip, w)? {
            let _ = writeln!(deck.text, "{}, 1, {fx:.12e}\n{}, 2, {fy:.12e}", n + 1, n + 1);
        }
        let _ = writeln!(deck.text, "*NODE PRINT, NSET=NOUT\nU\n*NODE PRINT, NSET=NCLAMP\nRF\n*END STEP");
        deck.times.push((j + 2) as f64);
    }
    let (res, rf, failure) = ccx::run_partial_reactions(&deck)?;
    if let Some(e) = failure {
        return Err(e);
    }
    let poses: Vec<Vec<SectionPose>> = res
        .iter()
        .map(|u| {
            let mut nodes: Vec<SectionPose> = sections.iter().map(|s| section_pose(&mesh, s, u)).collect();
            for k in 1..nodes.len() {
                let d = nodes[k].theta - nodes[k - 1].theta;
                let d = d - (2.0 * std::f64::consts::PI) * (d / (2.0 * std::f64::consts::PI)).round();
                nodes[k].theta = nodes[k - 1].theta + d;
            }
            nodes
        })
        .collect();
    let base = &poses[0];
    let tip0 = base[p.n];
    let mut c = [[0.0; 3]; 3];
    for j in 0..3 {
        let t = poses[j + 1][p.n];
        // the moment's couple (x forces linear in the face's reference y) turns with the face:
        // it applies M cos θ
        let f = if j == 2 { perturb[j] * tip0.theta.cos() } else { perturb[j] };
        let du = [t.x - tip0.x, t.y - tip0.y, t.theta - tip0.theta];
        for i in 0..3 {
            c[i][j] = du[i] / f;
        }
    }
    let joint_angle = (1..=p.n).map(|k| base[k].theta - base[k - 1].theta).collect();
    let pos = |i: usize| {
        let r = mesh.xy(i);
        [r[0] + res[0][&i][0], r[1] + res[0][&i][1]]
    };
    let span = (0..p.n)
        .map(|k| {
            let (a, b) = (pos(holes[2 * k]), pos(holes[2 * k + 1]));
            ((a[0] - b[0]).powi(2) + (a[1] - b[1]).powi(2)).sqrt()
        })
        .collect();
    Ok((FeState { tension, nodes: base.clone(), joint_angle, span, root: root_reaction(&mesh, kind, &rf[0]) }, c))
}
