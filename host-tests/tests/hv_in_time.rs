//! The HV ceiling in time, on the simulated board (`App` on `SimBoard`, 1 ms ticks in virtual
//! time): the control core integrates each stack's film state every tick and guards the
//! voltage so that the predicted thickness never falls below `s_hold`, whatever the history.
//! - random command histories (arm, disarm, volt, stop, param, runs of ticks; HV_HISTORIES of
//!   them, 10,000 by default): after every tick each channel's predicted s >= s_hold, every
//!   duty within the writer's ceiling now and the compiled cap (plain: the board's hold
//!   ceiling), and an f64 reference of the film driven by the written duties stays above the
//!   33 % limit with the field below the breakdown field; `stop` zeroes the duties at once;
//! - the film creeps under a held voltage and recovers after a stop;
//! - shaped actuation never thins past the target's thickness and settles faster than a plain
//!   step (settling to 1 % of the target thickness).
use finger_fw::board::{BOARD_CARD, BOARD_MARGIN, BOARD_Z0_MM, HV_FULL_SCALE_V};
use finger_fw::control::{hv_duty_cap, hv_duty_for, Control};
use finger_fw::sim::SimBoard;
use finger_fw::App;
use finger_model::material::{equilibrium_ratio, hold_ceiling, Relaxation, StackLaw, StackState, LIMIT_RATIO};
use host_tests::hv::{setpoints, settling_s, step_response};
use host_tests::sim_console::Out;

/// The testkit's xorshift64*: the histories are reproducible from their seed.
struct Rng(finger_model_testkit::material::Rng);
impl Rng {
    /// The generator's whole 64-bit output (the testkit's `next` keeps its top 53 bits).
    fn next(&mut self) -> u64 {
        self.0.next();
        self.0 .0.wrapping_mul(0x2545_F491_4F6C_DD1D)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
    fn unit(&mut self) -> f64 {
        self.0.next()
    }
}

/// The board's film in f64, driven by the voltages the written duties give: the reference.
struct Reference {
    law: StackLaw<f64>,
    relax: Relaxation<f64>,
    state: [StackState<f64>; 3],
    s_hold: f64,
}

impl Reference {
    fn new() -> Self {
        let law = StackLaw::new(BOARD_CARD, BOARD_Z0_MM as f64, BOARD_MARGIN as f64).unwrap();
        let relax = Relaxation::new(&law, 1e-3).unwrap();
        let s_hold = equilibrium_ratio(&law, hold_ceiling(&law, BOARD_MARGIN as f64)).unwrap();
        Reference { law, relax, state: [StackState::rest(); 3], s_hold }
    }

    /// One tick at the duties' voltages; checks the film and the field.
    fn tick(&mut self, duty: [u16; 3], max: u16, what: &dyn Fn() -> String) {
        for ch in 0..3 {
            let v = duty[ch] as f64 / max as f64 * HV_FULL_SCALE_V as f64;
            let st = &mut self.state[ch];
            st.advance(&self.law, &self.relax, v).unwrap_or_else(|e| panic!("reference refused {v} V: {e:?}; {}", what()));
            let s = st.s;
            assert!(s > LIMIT_RATIO && s >= self.s_hold * (1.0 - 1e-4), "reference s {s} (s_hold {}) at {v} V; {}", self.s_hold, what());
            let field = v / (s * self.law.z0);
            assert!(field <= self.law.breakdown_field(s), "field {field} V/mm at {v} V; {}", what());
        }
    }
}

/// What a history checks after every tick and command.
struct Checker {
    reference: Reference,
    s_hold: f32,
    hold_duty: u16,
    cap: u16,
    max: u16,
    /// A `param shaped 1` was taken in this history.
    shaped_ever: bool,
    log: Vec<String>,
}

impl Checker {
    fn new(a: &App<SimBoard>) -> Self {
        let max = a.board().hv[0].max;
        let c = a.control();
        Checker {
            reference: Reference::new(),
            s_hold: c.s_hold(),
            hold_duty: hv_duty_for(c.hold_ceiling_v(), max),
            cap: hv_duty_cap(max),
            max,
            shaped_ever: false,
            log: Vec::new(),
        }
    }

    fn check(&self, a: &App<SimBoard>) {
        let v = a.control().view();
        let now = a.control().duty_ceiling_now();
        for ch in 0..3 {
            let d = a.board().hv[ch].duty;
            assert!(v.stack_ratio[ch] >= self.s_hold, "ch{ch} s {} < s_hold {}; {:?}", v.stack_ratio[ch], self.s_hold, self.log);
            assert!(d <= self.cap && (d == 0 || d <= now[ch]), "ch{ch} duty {d} past {} / {}; {:?}", now[ch], self.cap, self.log);
            if !self.shaped_ever {
                assert!(d <= self.hold_duty, "ch{ch} duty {d} past the hold ceiling's {}; {:?}", self.hold_duty, self.log);
            }
        }
    }

    fn ticks(&mut self, a: &mut App<SimBoard>, n: u32) {
        let mut out = Out(String::new());
        for _ in 0..n {
            a.tick(1, &mut out);
            self.check(a);
            let duty = a.board().hv.map(|h| h.duty);
            let log = &self.log;
            self.reference.tick(duty, self.max, &|| format!("{log:?}"));
        }
    }

    /// One console line; the reply's first word.
    fn line(&mut self, a: &mut App<SimBoard>, l: &str) -> String {
        let mut out = Out(String::new());
        self.log.push(l.to_string());
        a.input(format!("{l}\n").as_bytes(), &mut out);
        self.check(a);
        out.0
    }
}

/// A random history from `seed`, checked all along.
fn history(seed: u64, hold: f32) {
    let mut rng = Rng(finger_model_testkit::material::Rng(seed.wrapping_mul(0x9E37_79B9_7F4A_7C15) | 1));
    let mut a = App::new(SimBoard::default());
    let mut c = Checker::new(&a);
    let ops = 4 + rng.below(12);
    for _ in 0..ops {
        match rng.below(20) {
            0..=2 => {
                c.line(&mut a, "arm");
            }
            3 => {
                c.line(&mut a, "disarm");
            }
            4 => {
                c.line(&mut a, if rng.below(2) == 0 { "stop" } else { "STOP now" });
                assert_eq!(a.board().hv.map(|h| h.duty), [0; 3], "stop: duties 0 at once; {:?}", c.log);
                assert!(!a.board().enable.high);
            }
            5..=9 => {
                let v = match rng.below(6) {
                    0 => hold as f64,
                    1 => 9990.0,
                    _ => rng.unit() * 1.2 * hold as f64,
                };
                let ch = ["1", "2", "3", "all"][rng.below(4) as usize];
                c.line(&mut a, &format!("volt {ch} {v:.1}"));
            }
            10 => {
                let slew = [100.0, 2000.0, 20_000.0, 100_000.0][rng.below(4) as usize];
                c.line(&mut a, &format!("param slew {slew}"));
            }
            11 => {
                let on = rng.below(2);
                let r = c.line(&mut a, &format!("param shaped {on}"));
                if on == 1 && r.starts_with("ok") {
                    c.shaped_ever = true;
                }
            }
            _ => {
                let n = match rng.below(50) {
                    0 => 5_000 + rng.below(15_000),
                    1..=9 => 100 + rng.below(1_500),
                    _ => 1 + rng.below(40),
                } as u32;
                c.ticks(&mut a, n);
            }
        }
    }
}

#[test]
fn random_histories_never_thin_past_s_hold_nor_write_past_the_ceiling() {
    let n = host_tests::plant_runs::histories();
    let first: u64 = std::env::var("HV_HISTORIES_SEED").ok().and_then(|s| s.parse().ok()).unwrap_or(1);
    let hold = App::new(SimBoard::default()).control().hold_ceiling_v();
    for seed in first..first + n {
        history(seed, hold);
    }
}

#[test]
fn shaped_actuation_never_undershoots_and_settles_faster_than_plain() {
    let c = Control::new(SimBoard::default(), 2000, 2000.0);
    let hold = c.hold_ceiling_v();
    let law = finger_fw::board::board_law().unwrap();
    for frac in [0.5f32, 0.8, 1.0] {
        let v = frac * hold;
        let s_target = equilibrium_ratio(&law, v).unwrap();
        let plain = step_response(v, false, 2000.0, 400);
        let shaped = step_response(v, true, 2000.0, 400);
        let min = shaped.iter().map(|x| x.0).fold(1.0f32, f32::min);
        assert!(min >= s_target, "{v} V: shaped thinned to {min} < target {s_target}");
        // the shaped voltage goes above the target's and comes back to it
        let vmax = shaped.iter().map(|x| x.1).fold(0.0f32, f32::max);
        assert!(vmax > v, "{v} V: shaped drove at most {vmax} V");
        // plain may still be creeping at the end of the run (then it is slower, whatever it takes)
        let tp = settling_s(&plain, s_target).unwrap_or(f64::INFINITY);
        let ts = settling_s(&shaped, s_target).expect("shaped settles within the run");
        println!("settle to 1 % at {v:.0} V (s_target {s_target:.4}): plain {tp:.2} s, shaped {ts:.2} s");
        assert!(ts < tp, "{v} V: shaped {ts} s, plain {tp} s");
    }
}

#[test]
fn the_film_creeps_under_a_held_voltage_and_recovers_after_stop() {
    let mut c = Control::new(SimBoard::default(), 2000, 2000.0);
    let v = 0.9 * c.hold_ceiling_v();
    assert!(c.apply(&setpoints(&c, [v; 3], false, 2000.0)));
    let at = |c: &mut Control<SimBoard>, ms: u32| {
        for _ in 0..ms {
            c.tick(c.now_ms());
        }
        c.view().stack_ratio[0]
    };
    let s5 = at(&mut c, 5_000);
    let s60 = at(&mut c, 55_000);
    assert!(s60 < s5 - 0.01, "creep under {v} V: {s5} -> {s60}");
    assert_eq!(c.view().volts[0], v, "held");
    c.stop();
    assert_eq!(c.board().hv.map(|h| h.duty), [0; 3]);
    let s_off = at(&mut c, 1);
    assert!(s_off > s60 && s_off < 1.0, "elastic recovery at once, not whole: {s_off}");
    let s_later = at(&mut c, 60_000);
    assert!(s_later > s_off + 0.005 && s_later <= 1.0, "recovers in time: {s_off} -> {s_later}");
}
