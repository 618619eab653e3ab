//! The model target: arbitrary parameters and inputs into the f64 model's forward solve,
//! inverse, contact and fmax.
//!
//! Input: a parameter set (each value the model's default scaled by 2^-6..2^6, or a special
//! value: 0, negative, NaN, infinities, extremes, or raw bits), then up to [`MAX_OPS`]
//! operations, each with its tension and voltages (fractions of fmax and of the ceiling, or
//! special values).
//!
//! Invariants:
//! - every call answers a typed error or a finite answer, never a panic;
//! - an answer's voltages are 0 or below the ceiling (`de::check_voltage`), and a voltage
//!   that is negative, not finite or at/past the ceiling is refused;
//! - a forward answer is in equilibrium (`Finger::equilibrium_residual`, the relative wrench
//!   imbalance, within `equilibrium_bound`; why that bound: docs/reliability.md);
//! - an inverse answer gives back its angles (forward of its tension and voltages, 1e-6 rad);
//! - a contact answer is in equilibrium under its tip load with the tip on the stop;
//! - fmax is finite and not negative.
//!
//! Its decoder (`run_ops`: the parameter set, then each op's byte and voltages) is shared with
//! the split targets (model_forward, model_inverse, model_contact, model_fmax: one check each,
//! their tensions on `linear_tension`'s scale or, for model_fmax, on fmax's; docs/reliability.md
//! "The model target split"); this target and its committed inputs are as they were.
//!
//! What it is not: the domain's property tests (model/tests/proptest_domain.rs), which draw
//! from the documented domain; this draws from everywhere.

use finger_model::inverse::contact_force;
use finger_model::{de, DeModulusRule, Finger, Method, Params, Solution, MAX_JOINTS, MAX_SUB};

pub const MAX_OPS: usize = 4;

/// Bytes read in order; zeros past the end.
pub(crate) struct Bytes<'a>(&'a [u8]);

impl Bytes<'_> {
    pub(crate) fn u8(&mut self) -> u8 {
        match self.0.split_first() {
            Some((&b, rest)) => {
                self.0 = rest;
                b
            }
            None => 0,
        }
    }
    pub(crate) fn raw_f64(&mut self) -> f64 {
        let mut b = [0u8; 8];
        for x in &mut b {
            *x = self.u8();
        }
        f64::from_le_bytes(b)
    }
    /// `unit` x 2^((s-120)/20) for s < 240, else a special value.
    pub(crate) fn scaled(&mut self, unit: f64) -> f64 {
        let s = self.u8();
        match s {
            0..=239 => unit * ((s as f64 - 120.0) / 20.0).exp2(),
            240 => 0.0,
            241 => -unit,
            242 => f64::NAN,
            243 => f64::INFINITY,
            244 => f64::NEG_INFINITY,
            245 => 1e-300,
            246 => 1e300,
            247 => unit,
            _ => self.raw_f64(),
        }
    }
    /// `top` x s/200 (s < 240: 0 to 1.2 x top), else a special value.
    pub(crate) fn fraction(&mut self, top: f64) -> f64 {
        let s = self.u8();
        match s {
            0..=239 => top * s as f64 / 200.0,
            240 => top,
            241 => top * (1.0 - 1e-12),
            242 => -1.0,
            243 => f64::NAN,
            244 => f64::INFINITY,
            245 => top * (1.0 + 1e-12),
            246 => 1e300,
            _ => self.raw_f64(),
        }
    }
}

pub(crate) fn params(b: &mut Bytes) -> Params<f64> {
    let d = Params::<f64>::default();
    let flags = b.u8();
    let base = if flags & 1 != 0 { Params::paper() } else { d };
    let mut p = base;
    // which values move: one bit per group, so that most inputs stay near a preset
    let moved = b.u8();
    if moved & 1 != 0 {
        p.n = 1 + (b.u8() as usize) % (MAX_JOINTS + 1); // 1..=MAX_JOINTS+1: one past the end
        p.m = 1 + (b.u8() as usize) % (MAX_SUB + 1);
    }
    if moved & 2 != 0 {
        p.l = b.scaled(base.l);
        p.b = b.scaled(base.b);
        p.w = b.scaled(base.w);
    }
    if moved & 4 != 0 {
        p.t_min = b.scaled(base.t_min);
        p.a = b.scaled(base.a);
        p.e = b.scaled(base.e);
    }
    if moved & 8 != 0 {
        p.e_b = b.scaled(base.e_b);
        p.nu_b = b.scaled(base.nu_b);
        p.span_floor = b.scaled(base.span_floor);
    }
    if moved & 16 != 0 {
        p.layers = b.u8() as u32 % 64;
        p.z0 = b.scaled(base.z0);
        p.g = b.scaled(base.g);
    }
    if moved & 32 != 0 {
        p.nu = b.scaled(base.nu);
        p.eps_r = b.scaled(base.eps_r);
        p.margin = b.fraction(1.0);
        p.v_supply = b.scaled(base.v_supply);
    }
    if moved & 64 != 0 {
        p.n_inc = b.u8() as u32 % 64;
    }
    p.plate = flags & 2 != 0;
    p.flex_links = flags & 4 != 0;
    if flags & 8 != 0 {
        p.de_rule = DeModulusRule::PaperEq3;
    }
    p
}

/// The voltages refused by `de::check_voltage`: negative, not finite, at or past the ceiling.
pub(crate) fn volts_refused(f: &Finger<f64>, v: &[f64]) -> bool {
    v.iter().enumerate().any(|(k, &x)| de::check_voltage(f.params(), k, x).is_err())
}

pub(crate) fn check_answer_volts(f: &Finger<f64>, v: &[f64], what: &str) {
    let ceiling = f.voltage_ceiling();
    for &x in v {
        assert!(x == 0.0 || (x > 0.0 && x < ceiling), "{what}: voltage {x} with ceiling {ceiling}");
    }
}

pub(crate) fn check_finite_solution(s: &Solution<f64>, what: &str) {
    let n = s.n;
    let finite = s.nodes[..=n].iter().all(|q| q.x.is_finite() && q.y.is_finite() && q.theta.is_finite())
        && s.joint_angle[..n].iter().all(|a| a.is_finite())
        && s.thickness[..n].iter().all(|a| a.is_finite())
        && s.tension.is_finite()
        && s.residual.is_finite()
        && s.cable_excursion.is_finite();
    assert!(finite, "{what}: non-finite answer {s:?}");
}

/// Runs one input; panics when an invariant breaks.
pub fn check(data: &[u8]) {
    run_ops(data, MAX_OPS, |c, op, v, refused, b| {
        // fmax at these voltages (every op needs it for its tension)
        let fmax = checked_fmax(c, v, refused);
        let scale = fmax.unwrap_or(1.0);
        let tension = b.fraction(scale);
        match op % 4 {
            0 => forward(&c.f, tension, v, refused),
            1 => inverse(&c.f, tension, v, c.len),
            2 => {
                let p0 = b.fraction(scale);
                contact(&c.f, p0, tension, v, refused, c.len);
            }
            _ => {}
        }
    });
}

/// A parameter set the model took, and what every op reads from it.
pub(crate) struct Case {
    pub f: Finger<f64>,
    /// The finger's length (n x l), mm: the equilibrium checks' scale.
    pub len: f64,
}

/// The model targets' shared start (one decoder for all of them): the parameter set (a refused
/// one ends the input: a typed refusal is all it asks), the ceiling's check, then up to
/// `max_ops` ops, each its op byte then one voltage per joint (fractions of the ceiling), handed
/// to `op` with whether `de::check_voltage` refuses them and the bytes that follow.
pub(crate) fn run_ops(data: &[u8], max_ops: usize, mut op: impl FnMut(&Case, u8, &[f64], bool, &mut Bytes)) {
    let mut b = Bytes(data);
    let p = params(&mut b);
    if std::env::var_os("FUZZ_VERBOSE").is_some() {
        eprintln!("{p:?}");
    }
    let f = match Finger::new(p) {
        Ok(f) => f,
        Err(_) => return, // typed refusal of the parameters
    };
    let n = f.params().n;
    let len = f.params().l * n as f64;
    let ceiling = f.voltage_ceiling();
    assert!(!(ceiling < 0.0) && !ceiling.is_nan(), "ceiling {ceiling} of {p:?}");
    let c = Case { f, len };
    for _ in 0..max_ops {
        let o = b.u8();
        if b.0.is_empty() && o == 0 {
            break;
        }
        let v: Vec<f64> = (0..n).map(|_| b.fraction(ceiling)).collect();
        let refused = volts_refused(&c.f, &v);
        op(&c, o, &v, refused, &mut b);
    }
}

/// fmax at these voltages, checked: never answered at refused voltages, finite and >= 0.
pub(crate) fn checked_fmax(c: &Case, v: &[f64], refused: bool) -> Option<f64> {
    match c.f.fmax(v) {
        Ok(l) => {
            assert!(!refused, "fmax answered at refused voltages {v:?} (ceiling {}): {l:?}", c.f.voltage_ceiling());
            assert!(l.tension.is_finite() && l.tension >= 0.0, "fmax {l:?} at {v:?}");
            Some(l.tension)
        }
        Err(_) => None,
    }
}

/// A tension scale that costs one compliance evaluation, not fmax's search: the tension that
/// would turn the softest joint by 1 rad linearly, `1 / (e x sum of its sub-elements' C33)`
/// (fmax's own unit: its search bound is 1000 of it). On the corpus fmax is 4e-4 to 98 of it
/// (median 1.5). At the voltages' compliances, or at 0 V where they are refused, else 1 N.
pub(crate) fn linear_tension(f: &Finger<f64>, v: &[f64]) -> f64 {
    let p = f.params();
    let Ok(c) = f.compliances(v).or_else(|_| f.compliances(&vec![0.0; p.n])) else { return 1.0 };
    let softest = (0..p.n).map(|k| 1.0 / (p.e * c.c[k][..p.m].iter().map(|x| x[2][2]).sum::<f64>())).fold(f64::INFINITY, f64::min);
    if softest.is_finite() && softest > 0.0 {
        softest
    } else {
        1.0
    }
}

/// The equilibrium checks' bound on `Finger::equilibrium_residual` (the posture's relative
/// wrench imbalance): 1e-6, plus what holes solved to the converged method's 1e-9 mm leave of
/// the cable's direction over the shortest span (1e-9 mm / span: near contact a span of
/// 3.4e-5 mm turns the cable 3e-5 rad; docs/reliability.md "The equilibrium check").
pub(crate) fn equilibrium_bound(s: &Solution<f64>) -> f64 {
    let shortest = s.span[..s.n].iter().fold(f64::INFINITY, |a, &b| a.min(b));
    1e-6 + 1e-9 / shortest
}

pub(crate) fn forward(f: &Finger<f64>, tension: f64, v: &[f64], refused: bool) {
    if let Ok(s) = f.solve(tension, v, Method::converged()) {
        assert!(!refused, "forward answered at refused voltages {v:?}");
        check_finite_solution(&s, "forward");
        check_answer_volts(f, &s.volts[..s.n], "forward");
        let r = f.equilibrium_residual(&s);
        let bound = equilibrium_bound(&s);
        assert!(
            matches!(r, Ok(r) if r <= bound),
            "forward P={tension} V={v:?}: not in equilibrium, {r:?} (bound {bound:e}; solve's residual {:e}, {} iterations)",
            s.residual,
            s.iterations
        );
    }
}

pub(crate) fn inverse(f: &Finger<f64>, tension: f64, v: &[f64], len: f64) {
    let n = f.params().n;
    // angles the forward model reaches (a reachable target), and a given tension or none
    let Ok(s) = f.solve(tension, v, Method::converged()) else { return };
    let given = if tension.to_bits() & 1 == 0 { Some(s.tension) } else { None };
    let _ = len;
    if let Ok(inv) = finger_model::solve_pose(f, &s.joint_angle[..n], given) {
        assert!(inv.tension.is_finite() && inv.tension >= 0.0, "inverse tension {}", inv.tension);
        check_answer_volts(f, &inv.volts[..n], "inverse");
        match f.solve(inv.tension, &inv.volts[..n], Method::converged()) {
            Ok(back) => {
                for k in 0..n {
                    let err = (back.joint_angle[k] - s.joint_angle[k]).abs();
                    assert!(err <= 1e-6, "inverse of P={tension} V={v:?}: joint {k} off by {err:e} rad (answer P={} V={:?})", inv.tension, &inv.volts[..n]);
                }
            }
            Err(e) => panic!("the forward refuses the inverse's answer P={} V={:?}: {e:?}", inv.tension, &inv.volts[..n]),
        }
    }
}

pub(crate) fn contact(f: &Finger<f64>, p0: f64, tension: f64, v: &[f64], refused: bool, len: f64) {
    let n = f.params().n;
    if let Ok(c) = contact_force(f, p0, &vec![0.0; n], tension, v) {
        assert!(!refused, "contact answered at refused voltages {v:?}");
        assert!(c.force.iter().all(|x| x.is_finite()), "contact force {:?}", c.force);
        check_finite_solution(&c.solution, "contact");
        let r = f.equilibrium_residual(&c.solution);
        let bound = equilibrium_bound(&c.solution);
        // the pinned solve holds the holes and the tip to an absolute 1e-11 mm a joint's pitch:
        // where the loads turn the softest joint by less than 1e-12 rad (tensions of 1e-84 N:
        // fuzz/regressions/model_contact/), the whole deflection is under that tolerance and a
        // relative imbalance is not resolved (F = 0 answers at once); there only finiteness
        let resolved = p0.max(tension) >= 1e-12 * linear_tension(f, v);
        assert!(!resolved || matches!(r, Ok(r) if r <= bound), "contact P0={p0} P={tension} V={v:?}: not in equilibrium, {r:?} (bound {bound:e})");
        let tip = c.solution.tip();
        let on = (tip.x - c.point[0]).hypot(tip.y - c.point[1]);
        assert!(on <= 1e-4 * len, "contact: tip {on:e} mm off the stop");
        // the branch the finger reaches: no hinge turned by more than 100° from the free posture
        // at P0 (the forward solve from rest; the jumps issue 55 found turned joints by 98° to
        // 2,150°: a buckled or coiled equilibrium of the pinned finger). The hinge's rotation,
        // Σ Δθ of its sub-elements: a slender flexible link bent by the cable (a 752 mm link in
        // the model corpus's b0e30eb4, 247° of its joint's 250°) is the forward's far-off class
        let free0 = f.solve(p0, &vec![0.0; n], Method::converged()).expect("contact answered, its free posture refused");
        let hinge = |s: &Solution<f64>, k: usize| s.q[k][..s.m].iter().map(|q| q[2]).sum::<f64>();
        // 180°, not 100°: a pinned finger bent into an S (a hinge turned 121-133°) is a physical
        // posture, the branch followed continuously (each tension solved from the free posture
        // alone gives the same smooth path: fuzz/regressions/model_contact/
        // contact-s-shape-hinge-turned-133-deg-physical); the coiled answers (541°, 2,170°) stay caught
        let wild = 180f64.to_radians();
        // (a free posture coiled past ±100° a joint is the forward's far-off class: not checked)
        let coiled = (0..n).any(|k| free0.joint_angle[k].abs() > wild);
        for k in 0..n {
            let (q, q0) = (hinge(&c.solution, k), hinge(&free0, k));
            assert!(
                coiled || (q - q0).abs() <= wild,
                "contact P0={p0} P={tension} V={v:?}: hinge {k} at {:.1} deg, free {:.1}",
                q.to_degrees(),
                q0.to_degrees()
            );
        }
        // the stop only pushes: the force has no component along the tip's approach (the free
        // tip's motion as the tension rises at P0, here by a forward difference of 1/32 of P0
        // and 1/4,096 of fmax; 5 % of |F|, and 1e-7 N a newton of tension, for the difference's angle), where the free posture is
        // not coiled past ±100° a joint (there a difference does not give the tangent)
        if let (false, Ok(end)) = (coiled, f.fmax(&vec![0.0; n])) {
            if let Ok(up) = f.solve(p0 + p0 / 32.0 + end.tension / 4096.0, &vec![0.0; n], Method::converged()) {
                let d = [up.tip().x - free0.tip().x, up.tip().y - free0.tip().y];
                let along = (c.force[0] * d[0] + c.force[1] * d[1]) / d[0].hypot(d[1]);
                assert!(
                    !(along > 0.05 * c.magnitude() + 1e-7 * (1.0 + p0 + tension)),
                    "contact P0={p0} P={tension} V={v:?}: the stop pulls on the tip ({along:e} N along the approach, |F| {:e})",
                    c.magnitude()
                );
            }
        }
    }
}
