//! The fixed-point forward solve under tension alone: per joint, Newton on the guide-hole
//! position with the float march's loop (`march_subs`) on the Q forms of `ByComplianceLoaded`
//! and `PoseFrame`, its turn rule without an FPU (docs/model.md "Which march to call"), then the chain of
//! links and the cable excursion. Same equations as the float model, Q formats of [`q`].
use super::q::{narrow, shr_round, Mm, Nmm, Nt, Rad, Scaled, Unit, Q};
use super::trig::{hypot, hypot_inv, sin_cos};
use crate::de;
use crate::error::Error;
use crate::finger::{march_subs, uniform_beam_compliance, Compliances, Finger, Frame, Pose, Solution, SubElement};
use crate::mat3;
use crate::mat3::Mat3;
use crate::params::{MAX_JOINTS, MAX_SUB};
use crate::real::Real;

/// Accumulator frac of the compliance products (sums of q = C w before one shift).
const ACC: i32 = 40;
/// Newton: converged when both hole residuals are within this many Q22 units (~4e-6 mm).
const TOL_RAW: i32 = 16;
const MAX_ITER: u32 = 30;
/// Forward-difference step of the 2x2 Jacobian, Q22 units (2^-8 mm).
const H_LOG2: i32 = 14;

/// A compliance matrix scaled row by row, for a wrench of ([`Nt`], [`Nt`], [`Nmm`]): row i's
/// sum `sum_j m[i][j] w_j` (raw words, 32x32 -> 64) is `q_i 2^t[i]`, with `t[i]` the largest
/// that keeps every `|m[i][j]| < 2^30` (the tiny entries keep the row's absolute resolution).
/// `d02`, `d12`: entries C02, C12 on their own scale (the moment arm's correction).
#[derive(Clone, Copy, Debug, Default)]
pub(super) struct CMat {
    pub(super) m: [[i32; 3]; 3],
    pub(super) t: [i32; 3],
    pub(super) d02: Scaled,
    pub(super) d12: Scaled,
}

/// The wrench's formats (frac bits) by column.
const W_FRAC: [i32; 3] = [Nt::FRAC, Nt::FRAC, Nmm::FRAC];

/// (mantissa in [2^52, 2^53), binary exponent e with |x| = mant 2^(e - 52)); None for 0,
/// subnormals, inf, NaN. Integer operations on the bits.
fn split(x: f64) -> Option<(i64, i32, bool)> {
    let bits = x.to_bits();
    let exp = ((bits >> 52) & 0x7ff) as i32;
    if exp == 0 || exp == 0x7ff {
        return None;
    }
    Some((((bits & ((1u64 << 52) - 1)) | (1u64 << 52)) as i64, exp - 1023, bits >> 63 != 0))
}

impl CMat {
    /// The matrix it scales (entry (i, j) = m[i][j] 2^(F_j - t[i])), in `R` (f32 arithmetic
    /// when `R` is f32: no soft-float f64 on the M3).
    fn value<R: Real>(&self) -> [[R; 3]; 3] {
        let mut v = [[R::zero(); 3]; 3];
        for i in 0..3 {
            for (j, fr) in W_FRAC.iter().enumerate() {
                let e = fr - self.t[i];
                v[i][j] = if R::EPS > 1e-10 {
                    // 2^e as two powers of two in f32's exponent range (|e| <= 252)
                    let pow2 = |k: i32| f32::from_bits(((127 + k.clamp(-126, 127)) as u32) << 23);
                    R::from_f64((self.m[i][j] as f32 * pow2(e / 2) * pow2(e - e / 2)) as f64)
                } else {
                    // 2^(F_j - t): |F_j - t| stays well inside f64's exponent range
                    R::from_f64(self.m[i][j] as f64 * f64::from_bits(((1023 + e) as u64) << 52))
                };
            }
        }
        v
    }

    fn new(c: &[[f64; 3]; 3]) -> CMat {
        let mut o = CMat { d02: Scaled::from_f64(c[0][2]), d12: Scaled::from_f64(c[1][2]), ..CMat::default() };
        for (i, ci) in c.iter().enumerate() {
            // |v| < 2^(e+1): |v| 2^(t - F_j) < 2^30 for t <= 29 - e + F_j
            let t = ci.iter().zip(W_FRAC).filter_map(|(&v, fr)| split(v).map(|(_, e, _)| 29 - e + fr)).min().unwrap_or(0);
            o.t[i] = t;
            for (j, (&v, fr)) in ci.iter().zip(W_FRAC).enumerate() {
                if let Some((mant, e, neg)) = split(v) {
                    // v 2^(t - F_j) = mant 2^(e - 52 + t - F_j)
                    let v = shr_round(mant, 52 - e - t + fr) as i32;
                    o.m[i][j] = if neg { -v } else { v };
                }
            }
        }
        o
    }
}

/// `-J^-1 r` for a Q30 Jacobian and a Q22 residual, in Q22; `None` when singular or out of
/// range. Entries past Q30's products (|J| > ~2.8: near contact the hole moves far more than
/// its guess) are scaled down by 2^-s first, the step by the same 2^-s after.
fn newton_step(j: &[[i64; 2]; 2], r: [Mm; 2]) -> Option<(i64, i64)> {
    step_q30(j, r).or_else(|| {
        let big = j.iter().flatten().map(|x| x.unsigned_abs()).max().unwrap_or(0);
        let s = (33 - big.leading_zeros() as i32).max(1) as u32;
        step_q30(&j.map(|row| row.map(|x| x >> s)), r).map(|(a, b)| (a >> s, b >> s))
    })
}

fn step_q30(j: &[[i64; 2]; 2], r: [Mm; 2]) -> Option<(i64, i64)> {
    let det = j[0][0].checked_mul(j[1][1])?.checked_sub(j[0][1].checked_mul(j[1][0])?)?;
    let det30 = shr_round(det, 30);
    if det30 == 0 {
        return None;
    }
    let (r0, r1) = (r[0].0 as i64, r[1].0 as i64);
    let n0 = j[1][1].checked_mul(r0)?.checked_sub(j[0][1].checked_mul(r1)?)?;
    let n1 = j[0][0].checked_mul(r1)?.checked_sub(j[1][0].checked_mul(r0)?)?;
    Some((-(n0.checked_div(det30)?), -(n1.checked_div(det30)?)))
}

/// A planar pose: x, y (mm), angle (rad).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct FixedPose {
    pub x: Mm,
    pub y: Mm,
    pub theta: Rad,
}

impl FixedPose {
    /// This pose moved by (dx, dy, dθ) given in its own frame.
    fn then(&self, dx: Mm, dy: Mm, dtheta: Rad) -> Self {
        let (s, c) = sin_cos(self.theta);
        FixedPose { x: self.x + narrow(c.wide(dx) - s.wide(dy), 52), y: self.y + narrow(s.wide(dx) + c.wide(dy), 52), theta: self.theta + dtheta }
    }
}

/// A finger prepared for fixed-point solves at one set of channel voltages.
#[derive(Clone, Debug)]
pub struct FixedFinger {
    pub(super) n: usize,
    pub(super) m: usize,
    e: Mm,
    span_floor: Mm,
    sub_len: Mm,
    link_len: Mm,
    hinge_len: Mm,
    c: [[CMat; MAX_SUB]; MAX_JOINTS],
    /// Joint k's compliances are joint k-1's (its state is the same).
    pub(super) same_as_prev: [bool; MAX_JOINTS],
    link_c: Option<CMat>,
}

/// The converged posture.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct FixedSolution {
    pub n: usize,
    /// Joint angles (hinge and link rotation), rad.
    pub joint_angle: [Rad; MAX_JOINTS],
    /// Node poses 0..=n (node n the tip).
    pub nodes: [FixedPose; MAX_JOINTS + 1],
    /// Cable excursion (hinge length minus span, summed), mm.
    pub cable_excursion: Mm,
    /// Newton iterations, all joints.
    pub iterations: u32,
    /// The tension solved at.
    pub tension: Nt,
    /// Each joint's converged guide hole (its hinge's frame), mm.
    pub holes: [[Mm; 2]; MAX_JOINTS],
}

impl FixedSolution {
    pub fn tip(&self) -> FixedPose {
        self.nodes[self.n]
    }
}

pub(super) use crate::finger::MarchError;

pub(super) fn cmat<R: Real>(m: &[[R; 3]; 3]) -> CMat {
    let mut v = [[0f64; 3]; 3];
    for i in 0..3 {
        for j in 0..3 {
            v[i][j] = m[i][j].to_f64();
        }
    }
    CMat::new(&v)
}

/// `C (f0, f1, m)` row `i` as a 64-bit sum at frac `cm.t[i]` (three products, no shift).
#[inline(always)]
fn row(cm: &CMat, i: usize, f0: Nt, f1: Nt, m: Nmm) -> i64 {
    (cm.m[i][0] as i64 * f0.0 as i64).saturating_add(cm.m[i][1] as i64 * f1.0 as i64).saturating_add(cm.m[i][2] as i64 * m.0 as i64)
}

/// A sub-element's loads in Q formats: the force in its frame and the cable's moment about
/// its undeflected distal end (the float `SubLoads`).
type FixedLoads = ([Nt; 2], Nmm);
/// A sub-element's displacement (q0, q1, q2) in Q formats.
type FixedDisp = (Mm, Mm, Rad);

/// The Q form of `ByComplianceLoaded`: q0 = C (f, m0), then the moment arm's own change
/// s = (-f1 q0_0 + f0 q0_1) / den, q = q0 + s C(:, 2); refuses |den| at or below 2^-20.
struct FixedByCompliance<'a>(&'a [CMat; MAX_SUB]);

impl SubElement<FixedLoads> for FixedByCompliance<'_> {
    type Sub = CMat;
    type Disp = FixedDisp;
    #[inline(always)]
    fn subs(&self) -> &[CMat; MAX_SUB] {
        self.0
    }
    #[inline(always)]
    fn equilibrium(&self, cj: &CMat, (f, m0): FixedLoads) -> Result<FixedDisp, MarchError> {
        let q0 = [row(cj, 0, f[0], f[1], m0), row(cj, 1, f[0], f[1], m0), row(cj, 2, f[0], f[1], m0)];
        // den = 1 + f_y C02 - f_x C12, at frac ACC
        let den = (1i64 << ACC).saturating_add(cj.d02.wide(f[1], ACC)).saturating_sub(cj.d12.wide(f[0], ACC));
        let den26 = shr_round(den, ACC - 26);
        if den26.abs() <= (1 << 6) {
            return Err(MarchError::Singular);
        }
        let (q0x, q0y) = (shr_round(q0[0], cj.t[0] - 22), shr_round(q0[1], cj.t[1] - 22));
        // frac 44 over den at frac 26: s at frac 18 (no left shift: f q reaches 2^59 at
        // hundreds of newtons)
        let num = (-(f[1].0 as i64)).saturating_mul(q0x).saturating_add((f[0].0 as i64).saturating_mul(q0y));
        let sm: Nmm = narrow(num.checked_div(den26).ok_or(MarchError::Singular)?, 18);
        let qx: Mm = narrow(q0[0].saturating_add(cj.m[0][2] as i64 * sm.0 as i64), cj.t[0]);
        let qy: Mm = narrow(q0[1].saturating_add(cj.m[1][2] as i64 * sm.0 as i64), cj.t[1]);
        let qt: Rad = narrow(q0[2].saturating_add(cj.m[2][2] as i64 * sm.0 as i64), cj.t[2]);
        Ok((qx, qy, qt))
    }
}

/// The Q form of `PoseFrame` under tension alone: the pose in the joint's proximal frame, its
/// (sin, cos), the cable's force `fc` toward the hole guess `b`.
struct FixedPoseFrame {
    b: [Mm; 2],
    fc: [Nt; 2],
    sub_len: Mm,
    pose: FixedPose,
    s: Unit,
    co: Unit,
}

impl Frame<FixedLoads, FixedDisp> for FixedPoseFrame {
    #[inline(always)]
    fn loads(&self) -> FixedLoads {
        let (pose, s, co, fc, l) = (self.pose, self.s, self.co, self.fc, self.sub_len);
        let d0 = [pose.x + co.mul_q(l), pose.y + s.mul_q(l)];
        let m0: Nmm = narrow((self.b[0] - d0[0]).wide(fc[1]).saturating_sub((self.b[1] - d0[1]).wide(fc[0])), 44);
        let f: [Nt; 2] = [narrow(co.wide(fc[0]) + s.wide(fc[1]), 52), narrow(co.wide(fc[1]) - s.wide(fc[0]), 52)];
        (f, m0)
    }
    #[inline(always)]
    fn advance(&mut self, (qx, qy, qt): FixedDisp) {
        let (p, s, co) = (self.pose, self.s, self.co);
        let ax = qx + self.sub_len;
        self.pose = FixedPose { x: p.x + narrow(co.wide(ax) - s.wide(qy), 52), y: p.y + narrow(s.wide(ax) + co.wide(qy), 52), theta: p.theta + qt };
        // the turn rule (`Real::turn`) on a core without an FPU: the sub-element's own
        // (sin, cos), composed
        let (sd, cd) = sin_cos(qt);
        (self.s, self.co) = (narrow(s.wide(cd) + co.wide(sd), 60), narrow(co.wide(cd) - s.wide(sd), 60));
    }
}

impl FixedFinger {
    /// Set-up (float, once per parameter or voltage change): the finger's compliances at
    /// `volts`, each entry scaled to its own exponent; lengths to Q22.
    pub fn new<R: Real>(f: &Finger<R>, volts: &[R]) -> Result<Self, Error> {
        let mut s = Self::empty();
        s.prepare(f, volts)?;
        Ok(s)
    }

    /// A finger with no joints, to be [`FixedFinger::prepare`]d in place.
    pub fn empty() -> Self {
        FixedFinger {
            n: 0,
            m: 0,
            e: Mm::ZERO,
            span_floor: Mm::ZERO,
            sub_len: Mm::ZERO,
            link_len: Mm::ZERO,
            hinge_len: Mm::ZERO,
            c: [[CMat::default(); MAX_SUB]; MAX_JOINTS],
            same_as_prev: [false; MAX_JOINTS],
            link_c: None,
        }
    }

    /// [`FixedFinger::new`] in place (no copy of the compliances on the stack: small-RAM
    /// targets). On an error `self` is left with no joints.
    pub fn prepare<R: Real>(&mut self, f: &Finger<R>, volts: &[R]) -> Result<(), Error> {
        self.n = 0;
        let p = f.params();
        let (n, m) = (p.n, p.m);
        if volts.len() != n {
            return Err(Error::Input { input: "voltages", reason: "one voltage per joint is required" });
        }
        // `Finger::compliances`, one joint at a time (`Finger::joint_stiffness`: C_hinge
        // without stacks)
        let stacks = p.layers > 0 && cfg!(feature = "de");
        let stack = de::Stack::new(p);
        for (k, &v) in volts.iter().enumerate() {
            stack.check(k + 1, v)?;
            let t = if stacks { stack.thickness(k + 1, v)? } else { R::zero() };
            let kj = f.joint_stiffness(t);
            for j in 0..m {
                self.c[k][j] = cmat(&kj.compliance(j)?);
            }
            self.same_as_prev[k] = k > 0 && (!stacks || v == volts[k - 1]);
        }
        let hinge_len = p.hinge_len();
        let link_len = p.l - hinge_len;
        self.link_c = if p.flex_links { Some(cmat(&uniform_beam_compliance(p.hinge_modulus(), p.w, p.b, link_len))) } else { None };
        let mm = |x: R| Mm::from_real(x);
        self.m = m;
        self.e = mm(p.e);
        self.span_floor = mm(p.span_floor);
        self.sub_len = mm(hinge_len / R::from_u32(m as u32));
        self.link_len = mm(link_len);
        self.hinge_len = mm(hinge_len);
        self.n = n;
        Ok(())
    }

    /// A joint's march (compliances `c`) at hole guess `b`: the hinge end and the hole it
    /// arrives at. The float march's loop (`march_subs`) over the Q forms of its
    /// `ByComplianceLoaded` and `PoseFrame`.
    pub(super) fn march(&self, c: &[CMat; MAX_SUB], tension: Nt, b: [Mm; 2]) -> Result<(FixedPose, [Mm; 2]), MarchError> {
        let e = self.e;
        let span_v = [b[0], b[1] - e];
        // the span and its reciprocal (no division), then the direction by two products
        let (span, inv) = hypot_inv(span_v[0], span_v[1]).ok_or(MarchError::Contact)?;
        if span < self.span_floor {
            return Err(MarchError::Contact);
        }
        let dir: [Unit; 2] = [narrow(span_v[0].wide(inv), 48), narrow(span_v[1].wide(inv), 48)];
        let fc: [Nt; 2] = [-dir[0].mul_q(tension), -dir[1].mul_q(tension)];
        let frame = FixedPoseFrame { b, fc, sub_len: self.sub_len, pose: FixedPose::default(), s: Unit::ZERO, co: Q::<30>(1 << 30) };
        let FixedPoseFrame { pose, s, co, .. } = march_subs(&FixedByCompliance(c), frame, &mut [(); MAX_SUB][..self.m], |_| ())?;
        let hole = [pose.x - s.mul_q(e), pose.y + co.mul_q(e)];
        if hole[0].is_sat() || hole[1].is_sat() || pose.theta.is_sat() || pose.x.is_sat() || pose.y.is_sat() {
            return Err(MarchError::Singular);
        }
        Ok((pose, hole))
    }

    fn residual(&self, c: &[CMat; MAX_SUB], tension: Nt, b: [Mm; 2]) -> Result<([Mm; 2], FixedPose, [Mm; 2]), MarchError> {
        let (end, hole) = self.march(c, tension, b)?;
        Ok(([b[0] - hole[0], b[1] - hole[1]], end, hole))
    }

    /// Damped Newton on joint k's hole position from `b`, forward-difference Jacobian kept
    /// while it converges fast (chord steps: one march per step).
    fn newton(&self, c: &[CMat; MAX_SUB], tension: Nt, mut b: [Mm; 2], iters: &mut u32) -> Result<(FixedPose, [Mm; 2]), MarchError> {
        let (mut r, mut end, mut hole) = self.residual(c, tension, b)?;
        let norm = |r: &[Mm; 2]| r[0].0.unsigned_abs().max(r[1].0.unsigned_abs());
        // the Jacobian is kept (chord steps) while each step cuts the residual at least 4x
        let mut jac = [[0i64; 2]; 2];
        let mut fresh = false;
        for _ in 0..MAX_ITER {
            if norm(&r) <= TOL_RAW as u32 {
                return Ok((end, hole));
            }
            *iters += 1;
            if !fresh {
                // J = I - d hole / d b, Q30 (the step is a power of two: exact scaling)
                let h = Q::<22>(1 << H_LOG2);
                for i in 0..2 {
                    let mut bh = b;
                    bh[i] = bh[i] + h;
                    let (rh, ..) = self.residual(c, tension, bh)?;
                    jac[0][i] = (rh[0].0 as i64 - r[0].0 as i64) << (30 - H_LOG2);
                    jac[1][i] = (rh[1].0 as i64 - r[1].0 as i64) << (30 - H_LOG2);
                }
            }
            // step = -J^-1 r (Q52 numerators over a Q30 determinant: Q22); an overflow is a
            // divergent step (the caller continues in load)
            let (d0, d1) = newton_step(&jac, r).ok_or(MarchError::Singular)?;
            let mut lambda = 0;
            loop {
                let bt = [b[0] + narrow(d0 >> lambda, 22), b[1] + narrow(d1 >> lambda, 22)];
                match self.residual(c, tension, bt) {
                    Ok((rt, et, ht)) if norm(&rt) < norm(&r) || lambda >= 6 => {
                        // a full step that cut the residual 4x keeps the Jacobian (chord)
                        fresh = lambda == 0 && norm(&rt).saturating_mul(4) <= norm(&r);
                        (b, r, end, hole) = (bt, rt, et, ht);
                        break;
                    }
                    Err(e) if lambda >= 6 => return Err(e),
                    _ => lambda += 1,
                }
            }
        }
        // not within the stop: still converged when the step left is (|J| large near contact:
        // the residual's own rounding, J times the hole's resolution, passes the stop)
        match newton_step(&jac, r) {
            _ if norm(&r) <= TOL_RAW as u32 => Ok((end, hole)),
            Some((d0, d1)) if d0.abs().max(d1.abs()) <= TOL_RAW as i64 => Ok((end, hole)),
            _ => Err(MarchError::Singular),
        }
    }

    /// A joint at the tension (from the hole `from` if given, else straight), by load continuation when Newton from the straight joint fails
    /// (the increment doubles on success, halves on failure, down to P / 1024).
    pub(super) fn joint(&self, c: &[CMat; MAX_SUB], tension: Nt, from: Option<[Mm; 2]>, iters: &mut u32) -> Result<(FixedPose, [Mm; 2]), MarchError> {
        let straight = [self.hinge_len, self.e];
        if let Some(b) = from {
            if let Ok(st) = self.newton(c, tension, b, iters) {
                return Ok(st);
            }
        }
        let mut last = match self.newton(c, tension, straight, iters) {
            Ok(st) => return Ok(st),
            Err(e) => e,
        };
        let (total, min_step) = (tension.0 as i64, (tension.0 as i64 >> 10).max(1));
        let (mut done, mut step, mut b) = (0i64, total / 8, straight);
        while done < total {
            let t = (done + step.max(min_step)).min(total);
            match self.newton(c, Q(t as i32), b, iters) {
                Ok((end, hole)) if t == total => return Ok((end, hole)),
                Ok((_, hole)) => {
                    (done, b, step) = (t, hole, step * 2);
                }
                Err(e) => {
                    last = e;
                    if step <= min_step {
                        break;
                    }
                    step /= 2;
                }
            }
        }
        Err(last)
    }

    /// Joint k's branch followed from 0 N up to `cap`: tension steps that double while they
    /// converge and halve when refused, each a Newton from the hole the last two points
    /// extrapolate to; stops when the step is below 2^-`rel_shift` of the tension. The largest
    /// tension held, its hole, and the refusal that ended the branch there (None: `cap` was held).
    pub(super) fn follow_branch(&self, k: usize, cap: Nt, rel_shift: u32) -> (Nt, [Mm; 2], Option<MarchError>) {
        let c = &self.c[k];
        let mut iters = 0u32;
        // the last two points held: (tension, hole)
        let (mut p, mut hole) = (0i64, [self.hinge_len, self.e]);
        let (mut p_prev, mut hole_prev) = (p, hole);
        let mut step = 1i64 << 20;
        loop {
            let t = (p + step).min(cap.0 as i64);
            // the secant predictor through the last two points (the straight hole from 0 N)
            let guess = if p > p_prev {
                let w = |a: Mm, b: Mm| Q(b.0 + (((b.0 as i64 - a.0 as i64) * (t - p)) / (p - p_prev)) as i32);
                [w(hole_prev[0], hole[0]), w(hole_prev[1], hole[1])]
            } else {
                hole
            };
            // a step that moves the span vector by more than a quarter of its length was too
            // long (near contact it could cross to the far side of the floor)
            let span_v = |h: &[Mm; 2]| [h[0].0 as i64, h[1].0 as i64 - self.e.0 as i64];
            let (s0, s1) = (span_v(&hole), self.newton(c, Q(t as i32), guess, &mut iters));
            let s1 = s1.and_then(|(_, h)| {
                let d = span_v(&h);
                let moved = (d[0] - s0[0]).abs().max((d[1] - s0[1]).abs());
                if 4 * moved <= s0[0].abs().max(s0[1].abs()) {
                    Ok(h)
                } else {
                    Err(MarchError::Contact)
                }
            });
            match s1 {
                Ok(h) => {
                    (p_prev, hole_prev, p, hole) = (p, hole, t, h);
                    if t >= cap.0 as i64 {
                        return (cap, hole, None);
                    }
                    step *= 2;
                }
                Err(e) => {
                    step /= 2;
                    if step <= (p >> rel_shift).max(1) {
                        return (Q(p as i32), hole, Some(e));
                    }
                }
            }
        }
    }

    /// A link's deflection under tension alone: (-P, 0, P e) in its own frame.
    pub(super) fn link_q(&self, tension: Nt) -> (Mm, Mm, Rad) {
        match &self.link_c {
            Some(lc) => {
                let pe: Nmm = tension.mul_q(self.e);
                let (w0, w1) = (-tension, Nt::ZERO);
                (narrow(row(lc, 0, w0, w1, pe), lc.t[0]), narrow(row(lc, 1, w0, w1, pe), lc.t[1]), narrow(row(lc, 2, w0, w1, pe), lc.t[2]))
            }
            None => (Mm::ZERO, Mm::ZERO, Rad::ZERO),
        }
    }

    /// The converged equilibrium under `tension` (N) alone.
    pub fn solve(&self, tension: Nt) -> Result<FixedSolution, Error> {
        self.solve_from(tension, None)
    }

    /// [`FixedFinger::solve`], each joint's Newton first from `holes[k]` (a converged hole
    /// nearby, e.g. its branch's), then as `solve` from the straight joint.
    pub(super) fn solve_from(&self, tension: Nt, from: Option<&[[Mm; 2]; MAX_JOINTS]>) -> Result<FixedSolution, Error> {
        if tension.0 < 0 || tension.is_sat() {
            return Err(Error::Input { input: "tension", reason: "must be >= 0 and within the fixed-point range" });
        }
        let n = self.n;
        let mut ends = [FixedPose::default(); MAX_JOINTS];
        let mut holes = [[Mm::ZERO; 2]; MAX_JOINTS];
        let mut iterations = 0;
        for k in 0..n {
            if self.same_as_prev[k] {
                ends[k] = ends[k - 1];
                holes[k] = holes[k - 1];
                continue;
            }
            let (end, hole) = self.joint(&self.c[k], tension, from.map(|h| h[k]), &mut iterations).map_err(|e| match e {
                MarchError::Contact => Error::Contact { joint: k + 1, tension: tension.to_report() },
                MarchError::Singular => Error::NotConverged { iterations, residual: f64::INFINITY },
            })?;
            ends[k] = end;
            holes[k] = hole;
        }
        let link_q = self.link_q(tension);
        let mut nodes = [FixedPose::default(); MAX_JOINTS + 1];
        let mut joint_angle = [Rad::ZERO; MAX_JOINTS];
        let mut excursion = Mm::ZERO;
        for k in 0..n {
            let e = ends[k];
            let hinge_end = nodes[k].then(e.x, e.y, e.theta);
            nodes[k + 1] = hinge_end.then(self.link_len + link_q.0, link_q.1, link_q.2);
            joint_angle[k] = e.theta + link_q.2;
            let span = hypot(holes[k][0], holes[k][1] - self.e);
            if span < self.span_floor {
                return Err(Error::Contact { joint: k + 1, tension: tension.to_report() });
            }
            excursion = excursion + (self.hinge_len - span);
        }
        if nodes[..=n].iter().any(|p| p.x.is_sat() || p.y.is_sat() || p.theta.is_sat()) {
            return Err(Error::Singular { what: "fixed-point solution (out of range)" });
        }
        Ok(FixedSolution { n, joint_angle, nodes, cable_excursion: excursion, iterations, tension, holes })
    }

    /// Joint k's sub-element end poses (its hinge's frame) at the converged `sol`: the march
    /// from the converged hole over the first j + 1 sub-elements ends at sub-element j's end.
    pub fn sub_element_ends(&self, sol: &FixedSolution, k: usize) -> Result<[FixedPose; MAX_SUB], Error> {
        let mut ends = [FixedPose::default(); MAX_SUB];
        if k >= self.n || sol.n != self.n {
            return Err(Error::Input { input: "joint", reason: "not a joint of this solution" });
        }
        // the march of the solve, unchanged, on a finger of j + 1 sub-elements
        let mut prefix = self.clone();
        for j in 0..self.m {
            prefix.m = j + 1;
            ends[j] = prefix.residual(&self.c[k], sol.tension, sol.holes[k]).map_err(|_| Error::Singular { what: "fixed-point solution (re-march)" })?.1;
        }
        Ok(ends)
    }

    /// The linearised tip stiffness (`Finger::tip_stiffness`, docs/model.md "Tip stiffness") at the
    /// converged fixed-point `sol`: the sub-element end poses and nodes from fixed point,
    /// then C_tip = Σ J C Jᵀ and its inverse once in `R` (the sub-element compliances this
    /// finger was prepared with, unscaled; `f`: the parameters it was prepared from).
    pub fn tip_stiffness<R: Real>(&self, f: &Finger<R>, sol: &FixedSolution) -> Result<Mat3<R>, Error> {
        let n = sol.n;
        if n != f.params().n || self.m != f.params().m || n != self.n {
            return Err(Error::Input { input: "solution", reason: "solved for other parameters" });
        }
        let pose = |p: &FixedPose| Pose { x: p.x.to_real(), y: p.y.to_real(), theta: p.theta.to_real() };
        let mut s = Solution { n, m: self.m, tension: sol.tension.to_real(), iterations: sol.iterations, ..Solution::empty() };
        let mut c = Compliances { n, m: self.m, c: [[mat3::zero(); MAX_SUB]; MAX_JOINTS], thickness: [R::zero(); MAX_JOINTS], volts: [R::zero(); MAX_JOINTS] };
        let sub_len: R = self.sub_len.to_real();
        for k in 0..n {
            let ends = self.sub_element_ends(sol, k)?;
            let mut from: Pose<R> = Pose::origin();
            for j in 0..self.m {
                // q from consecutive end poses: the step in the proximal end's frame
                let to = pose(&ends[j]);
                let (sn, cs) = from.theta.sin_cos();
                let (dx, dy) = (to.x - from.x, to.y - from.y);
                s.q[k][j] = [cs * dx + sn * dy - sub_len, cs * dy - sn * dx, to.theta - from.theta];
                c.c[k][j] = self.c[k][j].value();
                from = to;
            }
        }
        for k in 0..=n {
            s.nodes[k] = pose(&sol.nodes[k]);
        }
        // the links' deflection (`tip_compliance` walks the chain: sub-elements, then the link)
        let (lx, ly, lt) = self.link_q(sol.tension);
        for k in 0..n {
            s.links[k] = [lx.to_real(), ly.to_real(), lt.to_real()];
        }
        // C_tip is symmetric positive definite (Σ J C Jᵀ), as in `Finger::tip_stiffness`
        mat3::inverse_spd(&f.tip_compliance(&c, &s)).ok_or(Error::Singular { what: "tip compliance" })
    }
}

#[cfg(test)]
mod tests {
    use super::*;
    use crate::{Method, Params};

    /// The bench's scenes' models (m = 1 rigid links, the paper's; and the default, m = 8 with
    /// the plate modulus and flexible links), with and without stacks.
    fn params() -> [Params<f64>; 4] {
        let d = Params::default();
        let paper = |layers| Params { layers, m: 1, plate: false, flex_links: false, ..Params::default() };
        [paper(0), paper(4), d, Params { layers: 0, ..d }]
    }

    /// Every model of `params` at 0 V, a uniform 8 kV and mixed voltages (stacked models only
    /// above 0 V): the f64 finger, the voltages and the fixed-point finger built at them.
    fn cases() -> impl Iterator<Item = (Params<f64>, Finger<f64>, [f64; 3], FixedFinger)> {
        params().into_iter().flat_map(|p| {
            let f = Finger::new(p).unwrap();
            [[0.0; 3], [8000.0; 3], [9000.0, 5000.0, 0.0]]
                .into_iter()
                .filter(move |v| !(p.layers == 0 && v[0] > 0.0))
                .map(move |volts| (p, f, volts, FixedFinger::new(&f, &volts).unwrap()))
        })
    }

    #[test]
    fn tip_within_1e3_mm_of_the_f64_model() {
        let mut worst = 0f64;
        for (p, f, volts, ff) in cases() {
            for t in [0.05, 0.2, 0.5, 1.0, 2.0, 7.0] {
                let want = f.solve(t, &volts, Method::converged()).unwrap();
                let got = ff.solve(Nt::from_f64(t)).unwrap();
                let (tw, tg) = (want.tip(), got.tip());
                let d = libm::hypot(tw.x - tg.x.to_f64(), tw.y - tg.y.to_f64());
                worst = worst.max(d);
                assert!(d < 1e-3, "m={} layers={} {volts:?} P={t}: tip {:?} vs {:?}", p.m, p.layers, (tw.x, tw.y), (tg.x.to_f64(), tg.y.to_f64()));
                for k in 0..3 {
                    assert!((want.joint_angle[k] - got.joint_angle[k].to_f64()).abs() < 2e-5, "joint {k}");
                }
                assert!((want.cable_excursion - got.cable_excursion.to_f64()).abs() < 1e-4);
            }
        }
        assert!(worst > 0.0);
    }

    /// The tip stiffness from the fixed-point state against the f64 model's at its own solve:
    /// each diagonal term within 2e-5 relative.
    #[test]
    fn tip_stiffness_within_2e5_of_the_f64_model() {
        let mut worst = 0f64;
        for (p, f, volts, ff) in cases() {
            for t in [0.05, 0.5, 1.0, 7.0] {
                let want = f.tip_stiffness(&f.solve(t, &volts, Method::converged()).unwrap()).unwrap();
                let got = ff.tip_stiffness(&f, &ff.solve(Nt::from_f64(t)).unwrap()).unwrap();
                for i in 0..3 {
                    let rel = ((got[i][i] - want[i][i]) / want[i][i]).abs();
                    worst = worst.max(rel);
                    assert!(rel < 2e-5, "m={} layers={} {volts:?} P={t}: k{i}{i} {} vs {}", p.m, p.layers, got[i][i], want[i][i]);
                }
            }
        }
        assert!(worst > 0.0);
    }

    #[test]
    fn contact_and_bad_tension_are_typed_errors() {
        let f = Finger::new(params()[0]).unwrap();
        let ff = FixedFinger::new(&f, &[0.0; 3]).unwrap();
        assert!(matches!(ff.solve(Nt::from_f64(-1.0)), Err(Error::Input { .. })));
        assert!(ff.solve(Nt::from_f64(400.0)).is_err());
    }
}

#[cfg(test)]
mod edge_tests {
    use super::*;
    use crate::Params;

    /// Tensions across the format's range and past it, and a stiff finger: a number or a
    /// typed error, never a panic (debug builds check every overflow).
    #[test]
    fn any_tension_gives_a_number_or_a_typed_error() {
        for p in [Params::<f64>::default(), Params { m: 1, plate: false, flex_links: false, ..Params::default() }] {
            let f = Finger::new(p).unwrap();
            let ff = FixedFinger::new(&f, &[0.0; 3]).unwrap();
            for t in [0.0, 1e-6, 0.01, 3.0, 20.0, 60.0, 150.0, 300.0, 511.0, 600.0] {
                match ff.solve(Nt::from_f64(t)) {
                    Ok(s) => assert!(s.nodes[..=3].iter().all(|n| !n.x.is_sat() && !n.y.is_sat())),
                    Err(e) => assert!(matches!(e, Error::Contact { .. } | Error::NotConverged { .. } | Error::Singular { .. } | Error::Input { .. }), "{e:?}"),
                }
            }
        }
    }
}
