//! The soak: the property cases of model/testkit/src/domain.rs (forward, fmax, the
//! inverse round trip, contact) drawn at random, by default 1,000,000 of them, and the count of
//! each outcome (an answer, each typed refusal, each violation). Exits 1 on any violation.
//!
//! `cd host-tests && cargo run --example soak [-- <cases> [<seed>]]`
//!
//! The film's guard: `cargo run --release --example soak -- material [<histories> [<seed>]]`
//! runs 1,000,000 random voltage histories (model/testkit/src/material.rs) through the control
//! tick's rule, every hundredth also against the f64 reference.

use finger_model_testkit::domain;
use finger_model_testkit::material::Rng;
use std::collections::BTreeMap;

fn main() {
    let args: Vec<String> = std::env::args().collect();
    if args.get(1).map(String::as_str) == Some("material") {
        return material(&args[2..]);
    }
    let cases: u64 = args.get(1).map_or(1_000_000, |s| s.parse().expect("cases"));
    let mut rng = Rng(args.get(2).map_or(0x9E37_79B9_7F4A_7C15, |s| s.parse().expect("seed")) | 1);
    let fingers: Vec<_> = (0..64).map(|i| domain::finger(i & 1 == 1, 1 + (i >> 3), i & 2 == 2, i & 4 == 4)).collect();
    let contact_finger = domain::finger(false, 8, true, true);
    let mut counts: BTreeMap<String, u64> = BTreeMap::new();
    let mut first_violation = None;
    for i in 0..cases {
        let f = &fingers[(rng.next() * 64.0) as usize];
        let v = [rng.next(), rng.next(), rng.next()];
        let (kind, r) = match i % 4 {
            0 => ("forward", domain::forward(f, rng.next(), v)),
            1 => ("fmax", domain::fmax(f, v)),
            2 => ("inverse", domain::inverse(f, 0.02 + 0.58 * rng.next(), v.map(|x| 0.9 * x))),
            _ => ("contact", domain::contact(&contact_finger, 0.05 + 4.95 * rng.next(), rng.next(), v)),
        };
        let key = match r {
            Ok(o) => format!("{kind}: {o}"),
            Err(e) => {
                first_violation.get_or_insert(e);
                format!("{kind}: VIOLATION")
            }
        };
        *counts.entry(key).or_default() += 1;
        if (i + 1) % 100_000 == 0 {
            eprintln!("{} cases", i + 1);
        }
    }
    println!("{cases} cases");
    for (k, n) in &counts {
        println!("{n:>10}  {k}");
    }
    if let Some(e) = first_violation {
        println!("first violation: {e}");
        std::process::exit(1);
    }
}

/// The film's guard under random voltage histories; exits 1 on any violation.
fn material(args: &[String]) {
    use finger_model_testkit::material::guarded_history;
    let histories: u64 = args.first().map_or(1_000_000, |s| s.parse().expect("histories"));
    let mut rng = Rng(args.get(1).map_or(0x5DEE_CE66_D1CE_4E5B, |s| s.parse().expect("seed")) | 1);
    let (mut ticks, mut guarded, mut near, mut worst_ref, mut min_margin) = (0u64, 0u64, 0u64, 0f64, f64::INFINITY);
    for i in 0..histories {
        match guarded_history(&mut rng, i % 100 == 0) {
            Ok(o) => {
                ticks += o.ticks;
                guarded += o.guarded;
                near += (o.min_s_over_hold < 1.0 + 1e-3) as u64;
                worst_ref = worst_ref.max(o.max_ref_error);
                min_margin = min_margin.min(o.min_s_over_hold);
            }
            Err(e) => {
                println!("history {i}: VIOLATION: {e}");
                std::process::exit(1);
            }
        }
        if (i + 1) % 100_000 == 0 {
            eprintln!("{} histories", i + 1);
        }
    }
    println!("{histories} histories, {ticks} ticks, {guarded} guarded ticks, {near} histories within 0.1 % of s_hold");
    println!("thinnest predicted film / s_hold: {min_margin:.6}; largest |s - s_ref| (every 100th history): {worst_ref:.2e}");
}
