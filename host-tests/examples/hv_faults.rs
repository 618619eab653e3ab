//! Fault injection and soft films against the HV plant, at scale (docs/reliability.md
//! "Measured HV"): `cargo run --release --example hv_faults -- [FAULT_HISTORIES] [CLEAN]
//! [SOFT] [FIRST_SEED] [HOLD_RUNS] [HOLD_S]` (defaults 1,000,000 / 10,000 / 10,000 / 0 / 100 /
//! 900: the soak). Prints missed trips, the latency distribution per fault kind, false trips,
//! the soft films' worst thickness, and the fault-free holds near the ceiling (`ceiling_holds`:
//! HOLD_RUNS runs of three channels, each HOLD_S of real time on the card's film or one of its
//! spread: ceilings lowered, the sensed film's worst gap to the model's); every 10,000 fault
//! histories a progress line (seeds so far, missed, worst breakdown cut), so the soak can run
//! in parts over consecutive seed ranges.
use finger_fw::control::Fault;
use host_tests::plant_runs::{ceiling_holds, clean_history, fault_history, soft_film_history, Kind, SOFT_TIME_SCALE};
use std::time::Instant;

fn arg(k: usize, d: u64) -> u64 {
    std::env::args().nth(k).and_then(|a| a.parse().ok()).unwrap_or(d)
}

fn main() {
    let (n_fault, n_clean, n_soft, first) = (arg(1, 1_000_000), arg(2, 10_000), arg(3, 10_000), arg(4, 0));
    let (n_hold_runs, hold_s) = (arg(5, 100), arg(6, 900));
    let t0 = Instant::now();
    let mut lat: Vec<(Kind, u32)> = Vec::new();
    let mut missed = 0;
    let mut worst_breakdown = 0;
    for seed in first..first + n_fault {
        let r = fault_history(seed, 3000);
        match (r.fault, r.latency_us) {
            (Some(_), Some(l)) => {
                if r.kind == Kind::Breakdown {
                    worst_breakdown = worst_breakdown.max(l);
                }
                lat.push((r.kind, l))
            }
            _ => {
                missed += 1;
                eprintln!("missed: seed {seed} {:?}", r);
            }
        }
        if (seed + 1 - first) % 10_000 == 0 {
            println!("progress: seeds {first}..{}, missed {missed}, worst breakdown cut {worst_breakdown} µs ({:.0} s)", seed + 1, t0.elapsed().as_secs_f64());
        }
    }
    println!("fault histories: {n_fault}, missed trips: {missed} ({:.0} s)", t0.elapsed().as_secs_f64());
    for kind in [Kind::Breakdown, Kind::Stuck, Kind::Open, Kind::Leak] {
        let mut l: Vec<u32> = lat.iter().filter(|(k, _)| *k == kind).map(|(_, l)| *l).collect();
        l.sort_unstable();
        if l.is_empty() {
            continue;
        }
        let q = |p: f64| l[((l.len() - 1) as f64 * p) as usize];
        println!("  {kind:?}: n={} latency_us median={} p99={} max={}", l.len(), q(0.5), q(0.99), l[l.len() - 1]);
    }
    let t1 = Instant::now();
    let false_trips: Vec<(u64, Fault)> = (0..n_clean).filter_map(|s| clean_history(1_000_000_000 + s, 3000).map(|f| (s, f))).collect();
    println!(
        "fault-free histories: {n_clean} of 3 s, false trips: {} ({:.0} s) {:?}",
        false_trips.len(),
        t1.elapsed().as_secs_f64(),
        &false_trips[..false_trips.len().min(5)]
    );
    for guard in [true, false] {
        let t2 = Instant::now();
        let runs: Vec<_> = (0..n_soft).map(|s| soft_film_history(2_000_000_000 + s, 3000, SOFT_TIME_SCALE, guard)).collect();
        let bad = runs.iter().filter(|r| r.collapsed || r.s_min <= 2.0 / 3.0 || r.field_max >= 18.0).count();
        let s_min = runs.iter().map(|r| r.s_min).fold(1.0f32, f32::min);
        let e_max = runs.iter().map(|r| r.field_max).fold(0.0f32, f32::max);
        println!("soft films (G_eq 6.7..13.4 kPa, {SOFT_TIME_SCALE}x fast creep), guard {}: {n_soft} histories, past 2/3 or collapsed: {bad}, thinnest s {s_min:.4}, highest field {e_max:.2} V/um ({:.0} s)", if guard { "on" } else { "off" }, t2.elapsed().as_secs_f64());
    }
    let t3 = Instant::now();
    let holds = ceiling_holds(3_000_000_000 + first, n_hold_runs, hold_s as u32, 1.0, 2);
    let lowered: Vec<_> = holds.iter().filter(|(_, _, r)| r.lowered > 0 || r.fault.is_some()).collect();
    let gap = holds.iter().map(|(_, _, r)| r.worst_gap).fold(f32::NEG_INFINITY, f32::max);
    let s_min = holds.iter().map(|(_, _, r)| r.s_min).fold(1.0f32, f32::min);
    println!(
        "holds at 0.9-1.0 of the ceiling (card's film and its spread, G_eq 13.16..15.36 kPa): {} of {hold_s} s, lowered or faulted: {} {:?}, the sensed film at most {gap:.4} thinner than the model's, true film thinnest {s_min:.4} ({:.0} s)",
        3 * holds.len(),
        lowered.len(),
        &lowered[..lowered.len().min(5)],
        t3.elapsed().as_secs_f64()
    );
}
