//! Random histories of the control core against the HV plant (`finger_fw::plant`): faults
//! injected at random times (breakdown, a stuck module, an open stack, a leak), fault-free
//! histories with the plant's noise, and a film softer than the card. Shared by
//! tests/hv_measured.rs (a fixed count, fixed seeds) and the `hv_faults` example (the soak
//! and docs/reliability.md's figures).
use finger_fw::control::{Control, Fault};
use finger_fw::plant::{Inject, Plant};
use finger_fw::sim::SimBoard;

use crate::hv::setpoints;

/// How many random histories a history test runs: `HV_HISTORIES` when set (scripts/mutants runs
/// fewer per mutant), else 10,000.
pub fn histories() -> u64 {
    std::env::var("HV_HISTORIES").ok().and_then(|s| s.parse().ok()).unwrap_or(10_000)
}

/// A small deterministic generator (splitmix64).
pub struct Rng(u64);

impl Rng {
    pub fn new(seed: u64) -> Self {
        Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) ^ 0xD1B5_4A32_D192_ED03)
    }
    #[allow(clippy::should_implement_trait)] // a generator, never exhausted: not an iterator
    pub fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    /// Uniform in [a, b).
    pub fn range(&mut self, a: f32, b: f32) -> f32 {
        a + (b - a) * ((self.next() >> 40) as f32 / (1u64 << 24) as f32)
    }
    pub fn below(&mut self, n: u32) -> u32 {
        (self.next() % n as u64) as u32
    }
}

/// The core on the plant board, armed at `target` V per channel.
pub fn armed(plant: Plant, target: [f32; 3]) -> Control<SimBoard> {
    let mut c = Control::new(SimBoard::with_plant(plant), 2000, 2000.0);
    let sp = setpoints(&c, target, false, 2000.0);
    assert!(c.apply(&sp));
    c
}

/// Ticks of the core (the command side checks in every tick).
pub fn run(c: &mut Control<SimBoard>, ms: u32) {
    for _ in 0..ms {
        c.tick(c.now_ms());
    }
}

/// The kinds of fault a history injects.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Kind {
    Breakdown,
    Stuck,
    Open,
    Leak,
}

/// One fault history's outcome.
#[derive(Clone, Copy, Debug)]
pub struct FaultRun {
    pub kind: Kind,
    /// The fault latched (None: missed), and the latency from injection to the enable low, µs.
    pub fault: Option<Fault>,
    pub latency_us: Option<u32>,
}

/// A fault history: random targets, a random time after arming (slewing or held), a random
/// fault on a random channel; then up to `watch_ms` for the core to cut.
pub fn fault_history(seed: u64, watch_ms: u32) -> FaultRun {
    let mut r = Rng::new(seed);
    let target = [r.range(500.0, 5399.0), r.range(500.0, 5399.0), r.range(500.0, 5399.0)];
    let mut c = armed(Plant::new(seed as u32).unwrap(), target);
    run(&mut c, 20 + r.below(3000));
    let ch = r.below(3) as usize;
    // the fault on a channel above 500 V (a film at a few volts neither breaks down nor leaks
    // measurably)
    for _ in 0..3000 {
        if c.view().volts[ch] >= 500.0 {
            break;
        }
        run(&mut c, 1);
    }
    let kind = [Kind::Breakdown, Kind::Stuck, Kind::Open, Kind::Leak][r.below(4) as usize];
    let v_now = c.view().volts[ch].max(500.0);
    let what = match kind {
        Kind::Breakdown => Inject::Breakdown { clears_after_ms: if r.below(2) == 0 { Some(1 + r.below(5)) } else { None } },
        Kind::Stuck => Inject::Stuck(r.range(6_000.0, 9_000.0)),
        Kind::Open => Inject::Open,
        // 2..20 µA through the film at the voltage now: past the leakage bound
        Kind::Leak => Inject::Leak(v_now / (r.range(2.0, 20.0) * 1e-6)),
    };
    let plant = c.board_mut().plant.as_mut().expect("plant");
    plant.inject(ch, what).expect("injects");
    for _ in 0..watch_ms {
        c.tick(c.now_ms());
        if !c.view().enable {
            // the plant sees the enable low in its next tick
            c.tick(c.now_ms());
            break;
        }
    }
    let fault = c.view().fault.get();
    let plant = c.board().plant.as_ref().expect("plant");
    let latency_us = (!plant.fault_pending()).then_some(plant.trip_last_us);
    FaultRun { kind, fault, latency_us }
}

/// A fault-free history: random commands (targets, holds, disarms) for about `ms`; the fault
/// latched, if any (a false trip).
pub fn clean_history(seed: u64, ms: u32) -> Option<Fault> {
    let mut r = Rng::new(seed);
    let mut c = armed(Plant::new(seed as u32).unwrap(), [0.0; 3]);
    let mut t = 0;
    while t < ms {
        let target = [r.range(0.0, 5399.0), r.range(0.0, 5399.0), r.range(0.0, 5399.0)];
        let slew = [200.0, 2000.0, 20_000.0, 100_000.0][r.below(4) as usize];
        let shaped = r.below(4) == 0;
        let mut sp = setpoints(&c, target, shaped, slew);
        sp.armed = r.below(8) != 0;
        c.apply(&sp);
        let hold = 50 + r.below(800);
        run(&mut c, hold);
        t += hold;
        if c.view().fault.get().is_some() {
            break;
        }
    }
    c.view().fault.get()
}

/// The soft films creep this many times faster than the card's (the board's model keeps the
/// card's times): 3 s of board time are five times the film's slowest branch (61 s / 100).
pub const SOFT_TIME_SCALE: f32 = 100.0;

/// A soft-film history's worst: the thinnest the true film got, whether it collapsed, its
/// highest field (V/µm).
#[derive(Clone, Copy, Debug)]
pub struct FilmRun {
    pub g_eq_kpa: f32,
    pub s_min: f32,
    pub collapsed: bool,
    pub field_max: f32,
}

/// A film with G_eq in [half the card's, the card's] relaxing `time_scale` times faster than
/// the card, under random held targets up to the board's ceiling for about `ms`; the
/// thickness guard `guard` on or off.
pub fn soft_film_history(seed: u64, ms: u32, time_scale: f32, guard: bool) -> FilmRun {
    let mut r = Rng::new(seed);
    let g = r.range(6.7, 13.4);
    let mut plant = Plant::new(seed as u32).unwrap();
    plant.set_film(g, time_scale).expect("film");
    let mut c = armed(plant, [0.0; 3]);
    c.set_thickness_guard(guard);
    let hold_v = c.hold_ceiling_v();
    let mut t = 0;
    while t < ms {
        // mostly near the ceiling, held long: where a soft film is at risk
        let mut target = [0.0; 3];
        for v in target.iter_mut() {
            *v = if r.below(4) == 0 { r.range(0.0, hold_v) } else { r.range(0.95 * hold_v, hold_v - 1.0) };
        }
        let sp = setpoints(&c, target, r.below(4) == 0, [2000.0, 20_000.0][r.below(2) as usize]);
        c.apply(&sp);
        let hold = (ms / 8 + r.below(ms / 2)).min(ms - t);
        run(&mut c, hold);
        t += hold;
    }
    let truth = c.board().plant.as_ref().expect("plant").truth();
    let mut out = FilmRun { g_eq_kpa: g, s_min: 1.0, collapsed: false, field_max: 0.0 };
    for tr in truth {
        out.s_min = out.s_min.min(tr.s_min);
        out.collapsed |= tr.collapsed;
        out.field_max = out.field_max.max(tr.field_max_v_per_um);
    }
    out
}

/// The films of the card's stated spread (docs/materials.md "Equilibrium modulus"): G_eq from
/// the card's fit less its 95 % bound (13.4 - 0.24 kPa) to the stiffest of the three fits
/// (15.36 kPa), kPa.
pub const SPREAD_KPA: (f32, f32) = (13.16, 15.36);

/// A hold near the ceiling: how many channels had their ceiling lowered, the fault latched,
/// the most the sensed film read thinner than the model's once held (from 5 s of board time),
/// and the thinnest the true film got.
#[derive(Clone, Copy, Debug)]
pub struct HoldRun {
    pub lowered: u32,
    pub fault: Option<Fault>,
    pub worst_gap: f32,
    pub s_min: f32,
}

/// The plant's film at `g_kpa` (the card's branches), each channel held at `frac` of the
/// board's hold ceiling (at most 1 V under it: the ceiling is exclusive) for `film_s` of the
/// film's time, the film and the board's model creeping `time_scale` times faster than the
/// card (1: real time), armed after a random 0..500 ms.
pub fn ceiling_hold(seed: u64, g_kpa: f32, frac: [f32; 3], film_s: u32, time_scale: f32) -> HoldRun {
    let mut plant = Plant::new(seed as u32).unwrap();
    plant.set_film(g_kpa, time_scale).expect("film");
    let mut c = Control::new(SimBoard::with_plant(plant), 2000, 2000.0);
    assert!(c.set_film_time_scale(time_scale), "time scale {time_scale}");
    run(&mut c, (seed * 37 % 500) as u32);
    let hold = c.hold_ceiling_v();
    let target = frac.map(|f| (f * hold).min(hold - 1.0).floor());
    assert!(c.apply(&setpoints(&c, target, false, 2000.0)));
    let ticks = (film_s as f32 * 1000.0 / time_scale) as u32;
    // once held: the 2.7 s ramp and the slew's windows out of the running mean
    let held_from = 5000;
    let mut out = HoldRun { lowered: 0, fault: None, worst_gap: f32::NEG_INFINITY, s_min: 1.0 };
    let mut lowered = [false; 3];
    for t in 0..ticks {
        c.tick(c.now_ms());
        let v = c.view();
        let sense = v.sense.expect("a read-back");
        for ch in 0..3 {
            lowered[ch] |= sense.ceiling_v[ch] < hold;
            if t >= held_from && sense.stack_ratio[ch].is_finite() {
                out.worst_gap = out.worst_gap.max(v.stack_ratio[ch] - sense.stack_ratio[ch]);
            }
        }
        if v.fault.get().is_some() {
            break;
        }
    }
    out.lowered = lowered.iter().filter(|&&l| l).count() as u32;
    out.fault = c.view().fault.get();
    out.s_min = c.board().plant.as_ref().expect("plant").truth().iter().map(|t| t.s_min).fold(1.0, f32::min);
    out
}

/// `runs` holds of three channels from `seed0` ([`ceiling_hold`]): one run in three on the
/// card's own film, the others on a film drawn from [`SPREAD_KPA`]; each channel at a
/// fraction 0.9..1.0 of the ceiling, the third at the ceiling itself (1 V under it). On
/// `threads` threads, in seed order.
pub fn ceiling_holds(seed0: u64, runs: u64, film_s: u32, time_scale: f32, threads: u64) -> Vec<(u64, f32, HoldRun)> {
    let one = |seed: u64| {
        let mut r = Rng::new(seed);
        let g = if seed % 3 == 0 { finger_fw::board::BOARD_CARD.g_eq_mpa as f32 * 1e3 } else { r.range(SPREAD_KPA.0, SPREAD_KPA.1) };
        let frac = [r.range(0.9, 1.0), r.range(0.9, 1.0), 1.0];
        (seed, g, ceiling_hold(seed, g, frac, film_s, time_scale))
    };
    std::thread::scope(|s| {
        let parts: Vec<_> =
            (0..threads.max(1)).map(|k| s.spawn(move || (seed0 + k..seed0 + runs).step_by(threads.max(1) as usize).map(one).collect::<Vec<_>>())).collect();
        let mut all: Vec<_> = parts.into_iter().flat_map(|h| h.join().unwrap()).collect();
        all.sort_by_key(|x| x.0);
        all
    })
}
