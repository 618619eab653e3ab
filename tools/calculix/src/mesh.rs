//! The finger's plane mesh from `Params`: 8-node quadrilaterals (corner nodes, then midsides),
//! the notches' elliptical faces followed exactly at every node, the links as thick strips and
//! each DE stack as a bonded layer of E_de under the hinge's waist; and its extrusion to
//! 20-node bricks over half the width.
//!
//! What it is not: a general mesher. The geometry is a row of segments along x (link or
//! notch), each meshed by columns with the same number of rows, so neighbours share nodes.
//!
//! The stack (docs/model.md "Joint compliance with the stack": a layer of thickness t_k on the extensor side of the waist, centroid at
//! d = t_min/2 + t_k/2) is the region between the notch's extensor face and the plane
//! y = -(t_min/2 + t_k), bonded to the face: a lens under the waist that ends where the notch
//! is deeper than the stack. Where it ends its elements collapse to a point (8-node quads with
//! one edge of zero length, as crack-tip meshes use).

use finger_model::hinge::notch_thickness;
use finger_model::Params;
use std::collections::HashMap;

/// Mesh density: columns per notch and per link, element rows across the body and the stack.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Density {
    pub notch_cols: usize,
    pub link_cols: usize,
    pub rows: usize,
    pub stack_rows: usize,
    /// Element layers over the half width (3D only).
    pub layers: usize,
}

impl Density {
    /// What the tests use (seconds per ccx run).
    pub fn coarse() -> Self {
        Density { notch_cols: 8, link_cols: 3, rows: 2, stack_rows: 1, layers: 2 }
    }
    /// What the report uses (converged to well under 1 %: tests/convergence.rs).
    pub fn fine() -> Self {
        Density { notch_cols: 16, link_cols: 6, rows: 4, stack_rows: 2, layers: 4 }
    }
    /// Every count times `k`.
    pub fn times(self, k: usize) -> Self {
        Density {
            notch_cols: self.notch_cols * k,
            link_cols: self.link_cols * k,
            rows: self.rows * k,
            stack_rows: self.stack_rows * k,
            layers: self.layers * k,
        }
    }
}

/// One stretch of the body along x.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Segment {
    /// A uniform strip of thickness b, [x0, x1].
    Link { x0: f64, x1: f64 },
    /// A notch starting at x0 (length 2a), with a stack of this thickness (mm; 0: none).
    Notch { x0: f64, stack_mm: f64 },
}

#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Material {
    Body,
    Stack,
}

/// A plane mesh of 8-node quadrilaterals (CalculiX/Abaqus node order: corners counter-clockwise,
/// then the midsides of edges 1-2, 2-3, 3-4, 4-1).
#[derive(Clone, Debug, Default)]
pub struct Mesh2 {
    pub nodes: Vec<[f64; 2]>,
    /// Whether a node is (also) an element corner.
    pub corner: Vec<bool>,
    pub elems: Vec<([usize; 8], Material)>,
}

impl Mesh2 {
    fn node(&mut self, map: &mut HashMap<(i64, i64), usize>, x: f64, y: f64, corner: bool) -> usize {
        let key = ((x * 1e7).round() as i64, (y * 1e7).round() as i64);
        let id = *map.entry(key).or_insert_with(|| {
            self.nodes.push([x, y]);
            self.corner.push(false);
            self.nodes.len() - 1
        });
        self.corner[id] |= corner;
        id
    }

    /// Nodes with |x - x0| < tol.
    pub fn at_x(&self, x0: f64) -> Vec<usize> {
        (0..self.nodes.len()).filter(|&i| (self.nodes[i][0] - x0).abs() < 1e-6).collect()
    }

    /// The node at (x, y), if there is one within 1e-6 mm.
    pub fn find(&self, x: f64, y: f64) -> Option<usize> {
        (0..self.nodes.len()).find(|&i| (self.nodes[i][0] - x).abs() < 1e-6 && (self.nodes[i][1] - y).abs() < 1e-6)
    }
}

/// Depth of the stack below the body's extensor face at notch coordinate u in [0, 2a]:
/// `h = max(0, t_min/2 + t_k - t(u)/2)`.
fn stack_depth(p: &Params<f64>, stack: f64, u: f64) -> f64 {
    if stack <= 0.0 {
        return 0.0;
    }
    (p.t_min / 2.0 + stack - notch_thickness(p.b, p.t_min, p.a, u) / 2.0).max(0.0)
}

/// The column boundaries of a segment.
fn columns(p: &Params<f64>, seg: &Segment, d: &Density) -> Vec<f64> {
    match *seg {
        Segment::Link { x0, x1 } => (0..=d.link_cols).map(|i| x0 + (x1 - x0) * i as f64 / d.link_cols as f64).collect(),
        Segment::Notch { x0, stack_mm } => {
            // uniform in phi, x = a (1 + sin phi): dense where the faces are steep
            let mut xs: Vec<f64> = (0..=d.notch_cols)
                .map(|i| {
                    let phi = -std::f64::consts::FRAC_PI_2 + std::f64::consts::PI * i as f64 / d.notch_cols as f64;
                    p.a * (1.0 + phi.sin())
                })
                .collect();
            // the stack's ends: t(u) = t_min + 2 t_k
            let r = 1.0 - 2.0 * stack_mm / (p.b - p.t_min);
            if stack_mm > 0.0 && r > 0.0 {
                let u = (1.0 - r * r).sqrt();
                for e in [p.a * (1.0 - u), p.a * (1.0 + u)] {
                    let near = xs.iter().map(|&x| (x - e).abs()).fold(f64::MAX, f64::min);
                    let h = 0.25 * 2.0 * p.a / d.notch_cols as f64;
                    if near > 1e-9 {
                        // move the nearest boundary onto the end if it is close, else add one;
                        // an end close to the notch's own end is taken at it (a column of a few
                        // um beside a 10 mm link diverges in ccx)
                        let i = xs.iter().enumerate().min_by(|a, b| (a.1 - e).abs().total_cmp(&(b.1 - e).abs())).unwrap().0;
                        let at_notch_end = i == 0 || i == xs.len() - 1;
                        if near < h && !at_notch_end {
                            xs[i] = e;
                        } else if !(at_notch_end && near < h) {
                            xs.push(e);
                        }
                    }
                }
                xs.sort_by(f64::total_cmp);
            }
            xs.into_iter().map(|u| x0 + u).collect()
        }
    }
}

/// The plane mesh of these segments (in order along x, contiguous).
pub fn mesh2(p: &Params<f64>, segs: &[Segment], d: &Density) -> Mesh2 {
    let mut m = Mesh2::default();
    let mut map = HashMap::new();
    let ny = d.rows;
    let nd = d.stack_rows;
    for seg in segs {
        let xs = columns(p, seg, d);
        // body thickness and stack depth at x
        let shape = |x: f64| -> (f64, f64) {
            match *seg {
                Segment::Link { .. } => (p.b, 0.0),
                Segment::Notch { x0, stack_mm } => {
                    // the notch's ends exactly: x0 + 2a - x0 rounds off 2a, and the ellipse's
                    // thickness there (a square root at zero) would move the end's nodes off the
                    // link's, leaving the mesh in two pieces
                    let (u, l) = (x - x0, 2.0 * p.a);
                    let u = if u < 1e-9 * l {
                        0.0
                    } else if u > l * (1.0 - 1e-9) {
                        l
                    } else {
                        u
                    };
                    (notch_thickness(p.b, p.t_min, p.a, u), stack_depth(p, stack_mm, u))
                }
            }
        };
        for c in 0..xs.len() - 1 {
            let xc = [xs[c], 0.5 * (xs[c] + xs[c + 1]), xs[c + 1]];
            let has_stack = shape(xc[1]).1 > 1e-9;
            // node (i, r): i in 0..3 along the column, r the row index; body rows 0..=2ny,
            // stack rows -2nd..=0 below the body's extensor face
            let mut grid = |m: &mut Mesh2, i: usize, r: i64| -> usize {
                let (t, h) = shape(xc[i]);
                let y = if r >= 0 { -t / 2.0 + t * r as f64 / (2 * ny) as f64 } else { -t / 2.0 + h * r as f64 / (2 * nd) as f64 };
                let corner = i.is_multiple_of(2) && r.rem_euclid(2) == 0;
                m.node(&mut map, xc[i], y, corner)
            };
            let mut quad = |m: &mut Mesh2, r0: i64, mat: Material| {
                let n = [
                    grid(m, 0, r0),
                    grid(m, 2, r0),
                    grid(m, 2, r0 + 2),
                    grid(m, 0, r0 + 2),
                    grid(m, 1, r0),
                    grid(m, 2, r0 + 1),
                    grid(m, 1, r0 + 2),
                    grid(m, 0, r0 + 1),
                ];
                m.elems.push((n, mat));
            };
            for j in 0..ny {
                quad(&mut m, 2 * j as i64, Material::Body);
            }
            if has_stack {
                for j in 0..nd {
                    quad(&mut m, -2 * (nd as i64) + 2 * j as i64, Material::Stack);
                }
            }
        }
    }
    m
}

/// The finger's segments: per joint a notch (with its stack thickness) and a link.
pub fn finger_segments(p: &Params<f64>, stack_mm: &[f64]) -> Vec<Segment> {
    let mut s = Vec::new();
    for k in 0..p.n {
        let x0 = k as f64 * p.l;
        s.push(Segment::Notch { x0, stack_mm: stack_mm.get(k).copied().unwrap_or(0.0) });
        s.push(Segment::Link { x0: x0 + 2.0 * p.a, x1: x0 + p.l });
    }
    s
}

/// A 20-node brick mesh (CalculiX C3D20 order): the plane mesh extruded over z in [0, depth].
#[derive(Clone, Debug, Default)]
pub struct Mesh3 {
    pub nodes: Vec<[f64; 3]>,
    pub elems: Vec<([usize; 20], Material)>,
}

impl Mesh3 {
    pub fn at_x(&self, x0: f64) -> Vec<usize> {
        (0..self.nodes.len()).filter(|&i| (self.nodes[i][0] - x0).abs() < 1e-6).collect()
    }
    pub fn find(&self, x: f64, y: f64, z: f64) -> Option<usize> {
        (0..self.nodes.len()).find(|&i| {
            let n = self.nodes[i];
            (n[0] - x).abs() < 1e-6 && (n[1] - y).abs() < 1e-6 && (n[2] - z).abs() < 1e-6
        })
    }
}

/// Extrude `m` over z in [0, depth] with `layers` element layers.
pub fn extrude(m: &Mesh2, depth: f64, layers: usize) -> Mesh3 {
    let nz = 2 * layers;
    let mut out = Mesh3::default();
    // id[node][iz]: a midside node of the plane mesh exists only at even z levels
    let mut id = vec![vec![usize::MAX; nz + 1]; m.nodes.len()];
    for (i, n) in m.nodes.iter().enumerate() {
        for iz in 0..=nz {
            if iz % 2 == 0 || m.corner[i] {
                id[i][iz] = out.nodes.len();
                out.nodes.push([n[0], n[1], depth * iz as f64 / nz as f64]);
            }
        }
    }
    for (e, mat) in &m.elems {
        for l in 0..layers {
            let (z0, z1, zm) = (2 * l, 2 * l + 2, 2 * l + 1);
            let mut n = [0usize; 20];
            for k in 0..4 {
                n[k] = id[e[k]][z0];
                n[4 + k] = id[e[k]][z1];
                n[8 + k] = id[e[4 + k]][z0];
                n[12 + k] = id[e[4 + k]][z1];
                n[16 + k] = id[e[k]][zm];
            }
            out.elems.push((n, *mat));
        }
    }
    out
}
