//! Bench image for the cost of `Finger::fmax` on the target (docs/fmax-cost.md):
//! instructions of one fmax (the end of the equilibrium branch at given voltages), f32, for
//! the paper's model (m = 1, rigid links, E_b) and the default model (m = 8, plate modulus,
//! flexible links), at 0 V, uniform and mixed voltages and a tiny span floor; each case
//! without (`full`) and with the finger's branch table (`table`: `BranchTable::fmax`, as the
//! firmware; the table's build is reported once per model, `B <model> <ticks>`). Prints `CAL`,
//! then `F <case> <full|table> ok <ticks> <fmax N> <joint> <kind>` (or
//! `F <case> <full|table> err <ticks> <code>`), then `END`. Driven by
//! `cargo run --example fmax_cost` in host-tests.
#![no_std]
#![no_main]

use cortex_m_rt::entry;
use cortex_m_semihosting::hprintln;
use finger_model::inverse::{BranchTable, Options};
use finger_model::{BranchEnd, Finger, Params};

use bench::cycles;

fn run(name: &str, f: &Finger<f32>, table: Option<&BranchTable<f32>>, frac: [f32; 3]) {
    let top = f.voltage_ceiling() * (1.0 - 1e-4);
    let v = core::hint::black_box([frac[0] * top, frac[1] * top, frac[2] * top]);
    for method in ["full", "table"] {
        let t0 = cycles::now();
        let r = match (method, table) {
            ("full", _) => f.fmax(&v),
            (_, Some(t)) => t.fmax(&v),
            _ => continue,
        };
        let t1 = cycles::now();
        match core::hint::black_box(r) {
            Ok(b) => {
                let kind = match b.kind {
                    BranchEnd::LimitPoint => "limit-point",
                    BranchEnd::Contact => "contact",
                    BranchEnd::SearchBound => "search-bound",
                };
                hprintln!("F {} {} ok {} {} {} {}", name, method, t1 - t0, b.tension, b.joint, kind)
            }
            Err(e) => hprintln!("F {} {} err {} {}", name, method, t1 - t0, e.code()),
        }
    }
}

#[entry]
fn main() -> ! {
    bench::start!();
    let paper = Params::<f32> { m: 1, plate: false, flex_links: false, ..Params::default() };
    let real = Params::<f32> { m: 8, plate: true, flex_links: true, ..Params::default() };
    let tiny = Params::<f32> { span_floor: 1e-6, ..real };
    for (cfg, p) in [("m1-rigid", paper), ("m8-plate-flex", real), ("m8-plate-flex-floor1e-6", tiny)] {
        let f = match Finger::new(p) {
            Ok(f) => f,
            Err(e) => {
                hprintln!("B {} err 0 {}", cfg, e.code());
                continue;
            }
        };
        let t0 = cycles::now();
        let table = BranchTable::new(core::hint::black_box(&f), &Options::default());
        let t1 = cycles::now();
        let table = core::hint::black_box(table).ok();
        hprintln!("B {} {} {}", cfg, t1 - t0, if table.is_some() { "ok" } else { "err" });
        for (case, frac) in [("0V", [0.0; 3]), ("half", [0.5; 3]), ("top", [1.0; 3]), ("mixed", [0.0, 0.5, 1.0])] {
            let mut buf = [0u8; 48];
            let mut len = 0;
            for &b in cfg.as_bytes().iter().chain(b"/").chain(case.as_bytes()) {
                buf[len] = b;
                len += 1;
            }
            run(core::str::from_utf8(&buf[..len]).unwrap_or("?"), &f, table.as_ref(), frac);
        }
    }
    bench::end()
}
