//! The fixed-point forward solve's algorithm (model/src/fixed/forward.rs) in f32, step for
//! step: the same march, forward-difference Jacobian (step 2^-8 mm), chord rule, backtracking,
//! load continuation; the stop is the f32 model's (16 ulp of the finger's length: f32 cannot
//! resolve the fixed point's 16 x 2^-22 mm at these lengths). Only for the bench's
//! "same algorithm" comparison (docs/fixed-point.md); the model's own f32 solve is `Finger::solve`.
use finger_model::finger::uniform_beam_compliance;
use finger_model::{Finger, Real, MAX_JOINTS, MAX_SUB};

type M3x3 = [[f32; 3]; 3];
const H: f32 = 1.0 / 256.0;
const MAX_ITER: u32 = 30;

pub struct Twin {
    n: usize,
    m: usize,
    e: f32,
    span_floor: f32,
    sub_len: f32,
    link_len: f32,
    hinge_len: f32,
    c: [[M3x3; MAX_SUB]; MAX_JOINTS],
    same_as_prev: [bool; MAX_JOINTS],
    link_c: Option<M3x3>,
    tol: f32,
}

#[derive(Clone, Copy, Default)]
pub struct Pose {
    pub x: f32,
    pub y: f32,
    pub theta: f32,
}

impl Pose {
    fn then(&self, dx: f32, dy: f32, dt: f32) -> Pose {
        let (s, c) = self.theta.sin_cos();
        Pose { x: self.x + c * dx - s * dy, y: self.y + s * dx + c * dy, theta: self.theta + dt }
    }
}

pub struct TwinSolution {
    pub tip: Pose,
    pub joint_angle: [f32; MAX_JOINTS],
    pub cable_excursion: f32,
    pub iterations: u32,
}

fn row(c: &M3x3, i: usize, a: f32, b: f32, m: f32) -> f32 {
    c[i][0] * a + c[i][1] * b + c[i][2] * m
}

impl Twin {
    pub fn new(f: &Finger<f32>, volts: &[f32]) -> Option<Twin> {
        let p = f.params();
        let comp = f.compliances(volts).ok()?;
        let mut same_as_prev = [false; MAX_JOINTS];
        for k in 1..p.n {
            same_as_prev[k] = comp.c[k][..p.m] == comp.c[k - 1][..p.m];
        }
        let hinge_len = p.hinge_len();
        let link_len = p.l - hinge_len;
        Some(Twin {
            n: p.n,
            m: p.m,
            e: p.e,
            span_floor: p.span_floor,
            sub_len: hinge_len / p.m as f32,
            link_len,
            hinge_len,
            c: comp.c,
            same_as_prev,
            link_c: p.flex_links.then(|| uniform_beam_compliance(p.hinge_modulus(), p.w, p.b, link_len)),
            tol: 16.0 * f32::EPSILON * (hinge_len + p.e + p.l),
        })
    }

    fn march(&self, k: usize, t: f32, b: [f32; 2]) -> Option<(Pose, [f32; 2])> {
        let e = self.e;
        let sv = [b[0], b[1] - e];
        let span = (sv[0] * sv[0] + sv[1] * sv[1]).sqrt();
        if !(span >= self.span_floor) {
            return None;
        }
        let fc = [-(sv[0] / span) * t, -(sv[1] / span) * t];
        let mut pose = Pose::default();
        let (mut s, mut co) = (0.0f32, 1.0f32);
        for cj in self.c[k][..self.m].iter() {
            let d0 = [pose.x + co * self.sub_len, pose.y + s * self.sub_len];
            let m0 = (b[0] - d0[0]) * fc[1] - (b[1] - d0[1]) * fc[0];
            let f = [co * fc[0] + s * fc[1], co * fc[1] - s * fc[0]];
            let q0 = [row(cj, 0, f[0], f[1], m0), row(cj, 1, f[0], f[1], m0), row(cj, 2, f[0], f[1], m0)];
            let den = 1.0 + cj[0][2] * f[1] - cj[1][2] * f[0];
            if !(den.abs() > 1e-6) {
                return None;
            }
            let sm = (-f[1] * q0[0] + f[0] * q0[1]) / den;
            let (qx, qy, qt) = (q0[0] + cj[0][2] * sm, q0[1] + cj[1][2] * sm, q0[2] + cj[2][2] * sm);
            let ax = qx + self.sub_len;
            pose = Pose { x: pose.x + co * ax - s * qy, y: pose.y + s * ax + co * qy, theta: pose.theta + qt };
            // the fixed-point march's turn: the sub-element's own (sin, cos), composed
            let (sd, cd) = qt.sin_cos();
            (s, co) = (s * cd + co * sd, co * cd - s * sd);
        }
        let hole = [pose.x - s * e, pose.y + co * e];
        (hole[0].is_finite() && hole[1].is_finite() && pose.theta.is_finite()).then_some((pose, hole))
    }

    fn residual(&self, k: usize, t: f32, b: [f32; 2]) -> Option<([f32; 2], Pose, [f32; 2])> {
        let (end, hole) = self.march(k, t, b)?;
        Some(([b[0] - hole[0], b[1] - hole[1]], end, hole))
    }

    fn newton(&self, k: usize, t: f32, mut b: [f32; 2], iters: &mut u32) -> Option<(Pose, [f32; 2])> {
        let (mut r, mut end, mut hole) = self.residual(k, t, b)?;
        let norm = |r: &[f32; 2]| r[0].abs().max(r[1].abs());
        let mut jac = [[0f32; 2]; 2];
        let mut fresh = false;
        for _ in 0..MAX_ITER {
            if norm(&r) <= self.tol {
                return Some((end, hole));
            }
            *iters += 1;
            if !fresh {
                for i in 0..2 {
                    let mut bh = b;
                    bh[i] += H;
                    let (rh, ..) = self.residual(k, t, bh)?;
                    jac[0][i] = (rh[0] - r[0]) / H;
                    jac[1][i] = (rh[1] - r[1]) / H;
                }
            }
            let det = jac[0][0] * jac[1][1] - jac[0][1] * jac[1][0];
            if !(det != 0.0) {
                return None;
            }
            let d = [-(jac[1][1] * r[0] - jac[0][1] * r[1]) / det, -(jac[0][0] * r[1] - jac[1][0] * r[0]) / det];
            let mut lambda = 0;
            loop {
                let sc = 1.0 / (1u32 << lambda) as f32;
                let bt = [b[0] + d[0] * sc, b[1] + d[1] * sc];
                match self.residual(k, t, bt) {
                    Some((rt, et, ht)) if norm(&rt) < norm(&r) || lambda >= 6 => {
                        fresh = lambda == 0 && norm(&rt) * 4.0 <= norm(&r);
                        (b, r, end, hole) = (bt, rt, et, ht);
                        break;
                    }
                    None if lambda >= 6 => return None,
                    _ => lambda += 1,
                }
            }
        }
        (norm(&r) <= self.tol).then_some((end, hole))
    }

    fn joint(&self, k: usize, t: f32, iters: &mut u32) -> Option<(Pose, [f32; 2])> {
        let straight = [self.hinge_len, self.e];
        if let Some(st) = self.newton(k, t, straight, iters) {
            return Some(st);
        }
        let min_step = t / 1024.0;
        let (mut done, mut step, mut b) = (0.0f32, t / 8.0, straight);
        while done < t {
            let tt = (done + step.max(min_step)).min(t);
            match self.newton(k, tt, b, iters) {
                Some(st) if tt == t => return Some(st),
                Some((_, hole)) => (done, b, step) = (tt, hole, step * 2.0),
                None => {
                    if step <= min_step {
                        break;
                    }
                    step /= 2.0;
                }
            }
        }
        None
    }

    pub fn solve(&self, t: f32) -> Option<TwinSolution> {
        let n = self.n;
        let mut ends = [Pose::default(); MAX_JOINTS];
        let mut holes = [[0f32; 2]; MAX_JOINTS];
        let mut iterations = 0;
        // same lines as the fixed forward's `solve_from`: this module is that algorithm in f32, step for step
        for k in 0..n {
            if self.same_as_prev[k] {
                ends[k] = ends[k - 1];
                holes[k] = holes[k - 1];
                continue;
            }
            (ends[k], holes[k]) = self.joint(k, t, &mut iterations)?;
        }
        let lq = match &self.link_c {
            Some(lc) => [row(lc, 0, -t, 0.0, t * self.e), row(lc, 1, -t, 0.0, t * self.e), row(lc, 2, -t, 0.0, t * self.e)],
            None => [0.0; 3],
        };
        let mut node = Pose::default();
        let mut joint_angle = [0f32; MAX_JOINTS];
        let mut exc = 0.0;
        for k in 0..n {
            let e = ends[k];
            let he = node.then(e.x, e.y, e.theta);
            node = he.then(self.link_len + lq[0], lq[1], lq[2]);
            joint_angle[k] = e.theta + lq[2];
            let sv = [holes[k][0], holes[k][1] - self.e];
            let span = (sv[0] * sv[0] + sv[1] * sv[1]).sqrt();
            if !(span >= self.span_floor) {
                return None;
            }
            exc += self.hinge_len - span;
        }
        Some(TwinSolution { tip: node, joint_angle, cable_excursion: exc, iterations })
    }
}
