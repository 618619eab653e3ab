//! Bench image for the film's law in time on the target (docs/materials.md): instructions of
//! one channel's control tick (`material::guarded_tick`: the guard's bound, the warm-started
//! thickness, the branches' relaxation) and of the relaxation alone, f32, VHB 4905, 1 ms, for
//! each integrator. Prints `CAL`, then `T <integrator> <case> <ticks> <count>` (SysTick ticks
//! over `count` calls), then `END`. Driven by `cargo run --release --example material_report`
//! in host-tests.
#![no_std]
#![no_main]

use core::hint::black_box;
use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use finger_model::material::{guarded_tick, hold_ceiling, hold_ratio, Integrator, Relaxation, StackLaw, StackState, VHB_4905};

use bench::cycles;

const N: u32 = 200;

#[entry]
fn main() -> ! {
    bench::start!();
    let law = StackLaw::<f32>::new(&VHB_4905, 0.5, 0.9).unwrap();
    let s_hold = hold_ratio(&law).unwrap();
    let hold = hold_ceiling(&law, law.margin);
    for integrator in Integrator::ALL {
        let relax = Relaxation::with_integrator(&law, 0.001, integrator).unwrap();
        let mut st = StackState::<f32>::rest();
        // a ramp to the hold ceiling: the thickness moves every tick
        let t0 = cycles::now();
        for k in 0..N {
            let v = black_box(hold * (k as f32 / N as f32));
            let _ = black_box(guarded_tick(&law, &relax, &mut st, v, s_hold));
        }
        let t1 = cycles::now();
        hprintln!("T {} ramp {} {}", integrator.name(), t1 - t0, N);
        // a held voltage: the film creeps
        let t0 = cycles::now();
        for _ in 0..N {
            let _ = black_box(guarded_tick(&law, &relax, &mut st, black_box(hold), s_hold));
        }
        let t1 = cycles::now();
        hprintln!("T {} hold {} {}", integrator.name(), t1 - t0, N);
        let t0 = cycles::now();
        for _ in 0..N {
            relax.relax(black_box(&mut st));
        }
        let t1 = cycles::now();
        hprintln!("T {} relax {} {}", integrator.name(), t1 - t0, N);
    }
    bench::end()
}
