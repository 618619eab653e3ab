//! Bench image: every scene of `scenes.rs` with every solver variant this image was built
//! for (features f32, f64, fixed; trig from libm or micromath), the instruction count of each
//! solve from SysTick under `-icount shift=0`, printed over semihosting, one line per result:
//!
//! `R <scene> <scalar> <method> ok <solve_ticks> <setup_ticks> <tip_x> <tip_y> <a1> <a2> <a3> <iters>`
//! `R <scene> <scalar> <method> err <solve_ticks> <setup_ticks> <error code>`
//!
//! and under gravity, the converged forward started from an earlier answer (`warm_starts`):
//! `W <scene> <scalar> <case> ok <solve_ticks> <iters> <tip moved from the cold solve's, mm>`
//!
//! `setup` is `Finger::compliances` (DE thinning and the joint compliances for the scene's
//! voltages, once per voltage change); `solve` is `Finger::solve_with` (equilibrium, posture,
//! excursion). Angles in rad, positions in mm. The host (perf-report) turns ticks into
//! instructions with the `CAL` line and compares against its f64 reference.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use finger_model::{Finger, Method, Params, Real};

use bench::cycles;
#[cfg(feature = "fixed")]
mod fix;
use finger_scenes as scenes;

use scenes::{Scene, N_INC, SCENES};

fn method_name(m: &Method<f64>, buf: &mut [u8; 12]) -> usize {
    // tiny formatter: "conv" or "step<N>"
    match m {
        Method::Converged { .. } => {
            buf[..4].copy_from_slice(b"conv");
            4
        }
        Method::Stepping { n_inc } => {
            buf[..4].copy_from_slice(b"step");
            let mut digits = [0u8; 8];
            let (mut v, mut k) = (*n_inc, 0);
            loop {
                digits[k] = b'0' + (v % 10) as u8;
                k += 1;
                v /= 10;
                if v == 0 {
                    break;
                }
            }
            for i in 0..k {
                buf[4 + i] = digits[k - 1 - i];
            }
            4 + k
        }
    }
}

/// The methods every scene runs: stepping at each n_inc, then the converged solver.
fn methods() -> impl Iterator<Item = Method<f64>> {
    // `quick`: only the converged solver (the CI smoke test and profiling)
    let n_inc: &[u32] = if cfg!(feature = "quick") { &[] } else { N_INC };
    n_inc.iter().map(|&n| Method::Stepping { n_inc: n }).chain(core::iter::once(Method::converged()))
}

fn cast_method<S: Real>(m: Method<f64>) -> Method<S> {
    match m {
        // a tolerance below the scalar's resolution is raised to it (1e-9 is 0 in I16F16)
        Method::Converged { tol, max_iter } => Method::Converged { tol: S::from_f64(tol.max(S::EPS)), max_iter },
        Method::Stepping { n_inc } => Method::Stepping { n_inc },
    }
}

pub(crate) fn params(s: &Scene) -> Params<f64> {
    scenes::params(s)
}

/// Run one scene with scalar `S`. `prep` builds the finger and its compliances (in `S`, or in
/// f32 and cast for fixed point).
fn run_scene<S: Real>(name: &str, s: &Scene, prep: impl Fn(&Scene) -> Result<(Finger<S>, finger_model::Compliances<S>, u64), finger_model::Error>) {
    let (finger, comp, setup) = match prep(s) {
        Ok(v) => v,
        Err(e) => {
            hprintln!("R {} {} all err 0 0 {}", s.name, name, e.code());
            return;
        }
    };
    for m in methods() {
        let mut buf = [0u8; 12];
        let len = method_name(&m, &mut buf);
        let mname = core::str::from_utf8(&buf[..len]).unwrap_or("?");
        let method = cast_method::<S>(m);
        let tension = S::from_f64(s.tension);
        let t0 = cycles::now();
        let r = finger.solve_with(&comp, tension, [S::zero(); 2], method);
        // the result must exist before the second reading; a reference, so no copy is timed
        core::hint::black_box(&r);
        let t1 = cycles::now();
        match r {
            Ok(sol) => {
                let tip = sol.tip();
                let a = sol.joint_angles();
                hprintln!(
                    "R {} {} {} ok {} {} {:e} {:e} {:e} {:e} {:e} {}",
                    s.name,
                    name,
                    mname,
                    t1 - t0,
                    setup,
                    tip.x.to_f64(),
                    tip.y.to_f64(),
                    a[0].to_f64(),
                    a[1].to_f64(),
                    a[2].to_f64(),
                    sol.iterations
                );
            }
            Err(e) => hprintln!("R {} {} {} err {} {} {}", s.name, name, mname, t1 - t0, setup, e.code()),
        }
    }
    if finger.has_weight() {
        warm_starts(name, s, &finger, &comp);
    }
}

/// Under gravity, the converged forward started from an earlier answer (`Finger::solve_from`:
/// the board's last posture) at the scene's tension and voltages, after solves (not counted)
/// at fractions of the tension (`at_...`) and at 0 V (`0V`): `again`, the same solve twice;
/// `from-0.9P`, one before at 0.9 of the tension (the first start from an answer: its Broyden
/// estimate is the solve from the straight finger's, refused, formed again by forward
/// differences); `from-0.5P-0.9P`, two before (the estimate carried from the second); `from-0V`,
/// one at 0 V; `from-0V-0.9P`, one at 0 V then one at 0.9 of the tension. One line each:
/// `W <scene> <scalar> <case> ok <solve_ticks> <iters> <tip moved from the cold solve's, mm>`
/// (or `W ... err <ticks> <code>`).
fn warm_starts<S: Real>(name: &str, s: &Scene, f: &Finger<S>, comp: &finger_model::Compliances<S>) {
    let method = cast_method::<S>(Method::converged());
    let tension = S::from_f64(s.tension);
    let Ok(cold) = f.solve_with(comp, tension, [S::zero(); 2], method) else { return };
    let Ok(c0) = f.compliances(&[S::zero(); 3]) else { return };
    let cases: [(&str, &[(f64, bool)]); 5] = [
        ("again", &[(1.0, true)]),
        ("from-0.9P", &[(0.9, true)]),
        ("from-0.5P-0.9P", &[(0.5, true), (0.9, true)]),
        ("from-0V", &[(1.0, false)]),
        ("from-0V-0.9P", &[(1.0, false), (0.9, true)]),
    ];
    for (from, before) in cases {
        let mut last = None;
        if before.iter().any(|&(p, at_volts)| f.solve_from(if at_volts { comp } else { &c0 }, tension * S::from_f64(p), method, &mut last).is_err()) {
            hprintln!("W {} {} {} err 0 start", s.name, name, from);
            continue;
        }
        let t0 = cycles::now();
        let r = f.solve_from(comp, tension, method, &mut last);
        core::hint::black_box(&r);
        let t1 = cycles::now();
        match r {
            Ok(sol) => {
                let (a, b) = (sol.tip(), cold.tip());
                let moved = ((a.x - b.x) * (a.x - b.x) + (a.y - b.y) * (a.y - b.y)).sqrt();
                hprintln!("W {} {} {} ok {} {} {:e}", s.name, name, from, t1 - t0, sol.iterations, moved.to_f64())
            }
            Err(e) => hprintln!("W {} {} {} err {} {}", s.name, name, from, t1 - t0, e.code()),
        }
    }
}

/// Finger and compliances computed in `S` itself (floats).
#[allow(dead_code)]
fn prep_float<S: Real>(s: &Scene) -> Result<(Finger<S>, finger_model::Compliances<S>, u64), finger_model::Error> {
    let f = Finger::new(params(s).cast::<S>())?;
    let v = [S::from_f64(s.volts[0]), S::from_f64(s.volts[1]), S::from_f64(s.volts[2])];
    let t0 = cycles::now();
    let c = f.compliances(&v);
    let t1 = cycles::now();
    Ok((f, c?, t1 - t0))
}

#[entry]
fn main() -> ! {
    bench::start!(if cfg!(feature = "quick") { 1000 } else { 1_000_000 }, (if cfg!(feature = "quick") { 2000u32 } else { 2_000_000 }));
    // `quick`: one scene (bare finger, 1.0 N)
    let scenes = if cfg!(feature = "quick") { &SCENES[2..3] } else { SCENES };
    for s in scenes.iter() {
        #[cfg(feature = "f32")]
        run_scene::<f32>(<f32 as Real>::NAME, s, prep_float::<f32>);
        #[cfg(feature = "f64")]
        run_scene::<f64>(<f64 as Real>::NAME, s, prep_float::<f64>);
        #[cfg(feature = "fixed")]
        {
            run_scene::<fix::Q16>("i16f16", s, fix::prep::<fix::Q16>);
            run_scene::<fix::Q32>("i32f32", s, fix::prep::<fix::Q32>);
        }
    }
    bench::end()
}
