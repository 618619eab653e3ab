//! The voltage loop's step response against the plant (docs/firmware.md "The voltage loop"):
//! `cargo run --release --example hv_loop`. A step from 10 % to 90 % of the board's ceiling (the
//! slew at its 1e5 V/s maximum), for a module at its datasheet gain and 10 % weak or strong:
//! the measured voltage's 10-90 % rise, its overshoot, its time to settle within 1 %, and the
//! steady-state error (the ripple's mean taken off).
use finger_fw::plant::{Inject, Plant};
use host_tests::hv::setpoints;
use host_tests::plant_runs::{armed, run};

fn main() {
    for gain in [1.0f32, 0.9, 1.1] {
        let mut p = Plant::new(4).unwrap();
        p.inject(0, Inject::Gain(gain)).unwrap();
        let mut c = armed(p, [0.0; 3]);
        let hold = c.hold_ceiling_v();
        let (lo, hi) = (0.1 * hold, 0.9 * hold);
        let sp = setpoints(&c, [lo, 0.0, 0.0], false, 100_000.0);
        c.apply(&sp);
        run(&mut c, 1500);
        let sp = setpoints(&c, [hi, 0.0, 0.0], false, 100_000.0);
        c.apply(&sp);
        let mut v = Vec::new();
        for _ in 0..1500 {
            run(&mut c, 1);
            v.push(c.board().plant.as_ref().unwrap().truth()[0].volts);
        }
        let at = |f: f32| v.iter().position(|&x| x >= lo + f * (hi - lo)).map(|k| k + 1);
        let (t10, t90) = (at(0.1).unwrap_or(0), at(0.9).unwrap_or(0));
        let peak = v.iter().cloned().fold(0.0f32, f32::max);
        // settled: within 1 % of the target, ripple's 100 V below it allowed, from then on
        let band = 0.01 * hi;
        let settle = v.iter().rposition(|&x| x > hi + band || x < hi - finger_fw::control::sense::RIPPLE_PP_V - band).map(|k| k + 1).unwrap_or(0);
        let tail = &v[v.len() - 200..];
        let mean = tail.iter().sum::<f32>() / tail.len() as f32;
        let err = (mean - (hi - finger_fw::control::sense::RIPPLE_PP_V / 2.0)) / hi * 100.0;
        println!(
            "gain {gain:.1}: step {lo:.0} -> {hi:.0} V: rise 10-90 % {} ms, overshoot {:.2} %, settled (1 %, ripple band) after {settle} ms, steady-state error {err:+.2} % (fault {:?})",
            t90 - t10,
            (peak - hi).max(0.0) / hi * 100.0,
            c.view().fault.get()
        );
    }
}
