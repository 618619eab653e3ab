//! Lean image: what one scene needs and nothing else, for the flash/RAM table of
//! docs/performance.md. One solve of the paper's 1.0 N scene with the converged solver, in
//! f32 (or fixed point with the `fixed` feature), with or without DE code (`de` feature);
//! the result leaves through semihosting as raw bits (no float formatting).
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::debug;
#[cfg(not(feature = "fixed"))]
use finger_model::Finger;
use finger_model::{Method, Params, Real};

#[cfg(feature = "fixed")]
#[allow(dead_code)]
mod fix;
use finger_scenes as scenes;
#[cfg(feature = "fixed")]
mod cycles_stub {
    pub fn now() -> u64 {
        0
    }
}
#[cfg(feature = "fixed")]
use cycles_stub as cycles;
fn params(s: &scenes::Scene) -> Params<f64> {
    scenes::params(s)
}

#[panic_handler]
fn panic(_: &core::panic::PanicInfo) -> ! {
    debug::exit(debug::EXIT_FAILURE);
    loop {}
}

fn layers() -> u32 {
    if cfg!(feature = "de") {
        4
    } else {
        0
    }
}

fn report(ok: bool, y: f64) {
    let bits = y.to_bits();
    let mut buf = [0u8; 17];
    for i in 0..16 {
        let d = ((bits >> (60 - 4 * i)) & 0xf) as u8;
        buf[i] = if d < 10 { b'0' + d } else { b'a' + d - 10 };
    }
    buf[16] = b'\n';
    let _ = ok;
    cortex_m_semihosting::hio::hstdout().map(|mut o| o.write_all(&buf)).ok();
}

#[entry]
fn main() -> ! {
    let tension = core::hint::black_box(1.0f64);
    #[cfg(not(feature = "fixed"))]
    let y = {
        let s = scenes::Scene { name: "", layers: layers(), tension, volts: [0.0; 3], fidelity: false, gravity: None };
        let f = Finger::new(params(&s).cast::<f32>());
        f.and_then(|f| f.solve(tension as f32, &[0.0; 3], Method::converged())).map(|s| s.tip().y.to_f64())
    };
    #[cfg(feature = "fixed")]
    let y = {
        let s = scenes::Scene { name: "", layers: layers(), tension, volts: [0.0; 3], fidelity: false, gravity: None };
        fix::prep::<fix::Q16>(&s).and_then(|(f, c, _)| {
            // the tolerance at the scalar's resolution (the default 1e-9 mm is 0 in I16F16)
            let m = Method::Converged { tol: fix::Q16::from_f64(<fix::Q16 as Real>::EPS), max_iter: 200 };
            f.solve_with(&c, fix::Q16::from_f64(tension), [fix::Q16::from_f64(0.0); 2], m).map(|s| s.tip().y.to_f64())
        })
    };
    match y {
        Ok(y) => report(true, y),
        Err(_) => report(false, f64::NAN),
    }
    debug::exit(debug::EXIT_SUCCESS);
    loop {
        cortex_m::asm::wfi();
    }
}
