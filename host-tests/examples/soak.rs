//! The soak (issue 13): the property cases of model/testkit/src/domain.rs (forward, fmax, the
//! inverse round trip, contact) drawn at random, by default 1,000,000 of them, and the count of
//! each outcome (an answer, each typed refusal, each violation). Exits 1 on any violation.
//!
//! `cd host-tests && cargo run --example soak [-- <cases> [<seed>]]`

use finger_model_testkit::domain;
use std::collections::BTreeMap;

/// xorshift64*: a uniform number in [0, 1).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> f64 {
        self.0 ^= self.0 >> 12;
        self.0 ^= self.0 << 25;
        self.0 ^= self.0 >> 27;
        (self.0.wrapping_mul(0x2545_F491_4F6C_DD1D) >> 11) as f64 / (1u64 << 53) as f64
    }
}

fn main() {
    let args: Vec<String> = std::env::args().collect();
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
