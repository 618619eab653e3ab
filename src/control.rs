//! The control core: the one owner of the outputs. Runs every 1 ms tick at the highest
//! priority (the chip's SysTick task; `App::tick` on the host).
//!
//! What it is: the single writer of the HV duties (`Control::write_hv_duty_checked`), the
//! slew of the HV values toward the command side's setpoints (at most `slew` x 1 ms per tick, whatever
//! else runs), the stacks in time ([`Stacks`]: each channel's film state integrated every
//! tick, and the guard that keeps it above its floor), the servo following the slewed
//! voltages, the disarm ramp, the emergency stop and the watchdog feed (only while the
//! command side has checked in within [`CHECKIN_BOUND_MS`]).
//!
//! What it is not: the console or the model. The command side ([`crate::app::Commands`])
//! plans [`Setpoints`]; the core takes them ([`Control::apply`]) unless a stop came after the
//! command began (its `epoch` is stale), and reports back a [`View`].

use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;

use crate::board::{Board, HV_CHANNELS, HV_FULL_SCALE_V, HV_LIMIT_V, HV_MAX_V, HV_ZERO_DUTY_PCT};

pub mod fault;
pub mod hv_loop;
pub mod sense;
pub mod stacks;
// the Cortex-M3 image's checks, and the host's (its tests)
#[cfg(any(m3, not(target_os = "none")))]
pub mod trip;
pub mod watch;
pub use fault::{Fault, Latched};
pub use stacks::Stacks;

/// What the core makes of the read-back, per channel (boards with one; docs/firmware.md).
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SenseView {
    /// The measured voltage (V) and return current (µA), the tick's means.
    pub volts: [f32; HV_CHANNELS],
    pub current_ua: [f32; HV_CHANNELS],
    /// The sensed thickness stretch (NaN until measured).
    pub stack_ratio: [f32; HV_CHANNELS],
    /// The channel's ceiling now, V: the hold ceiling lowered by its thickness guard.
    pub ceiling_v: [f32; HV_CHANNELS],
    /// The sensed film was thinner than the model's past the bound (`watch::DISAGREE_S`).
    pub disagreed: [bool; HV_CHANNELS],
}

/// A change the plant's test console asks of the board's plant (`plant ...`).
#[cfg(not(feature = "hw"))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum PlantRequest {
    Film { g_eq_kpa: f32, time_scale: f32 },
    Inject(usize, crate::plant::Inject),
}

/// What `plant status` shows of the plant: per channel its true voltage (V), current (µA)
/// and thickness stretch, and its film's G_eq (kPa).
#[cfg(not(feature = "hw"))]
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct PlantView {
    pub volts: [f32; HV_CHANNELS],
    pub current_ua: [f32; HV_CHANNELS],
    pub s: [f32; HV_CHANNELS],
    pub film_kpa: f32,
}

/// The read-back's per-channel state in the core.
#[cfg(not(m3))]
#[derive(Clone, Copy)]
struct Sensing {
    /// The board has a read-back (its first `hv_sense` answered).
    present: bool,
    /// The thickness guard acts (tests switch it off: feature `hv-door`).
    guard_on: bool,
    est: [sense::Estimator; HV_CHANNELS],
    watch: [watch::Watch; HV_CHANNELS],
    guard: [watch::ThicknessGuard; HV_CHANNELS],
    vloop: [hv_loop::VoltageLoop; HV_CHANNELS],
    cal: [sense::MonitorCal; HV_CHANNELS],
    /// Each stack's capacitance at 0 V, pF (stored; the board's constant until calibrated).
    c0_pf: [f32; HV_CHANNELS],
    /// The voltage the loop drove each channel to in the tick just ended, V.
    drive: [f32; HV_CHANNELS],
    /// What the loop asked of each module this tick, and whether the slew held it back (the
    /// module not yet given the chance to follow its command: `watch::Watch::check`).
    ask: [hv_loop::Ask; HV_CHANNELS],
    /// Each channel's time in its hold, ms (0: not held): the ripple's phase, from 0 V below
    /// the guarded value, so it starts without a step.
    ripple_ms: [u32; HV_CHANNELS],
    /// Windows the estimator had closed when the guard last looked.
    seen_windows: [u32; HV_CHANNELS],
    view: SenseView,
    /// Re-arming after a read-back fault runs the low-voltage check first: until this tick,
    /// no channel above `LOW_CHECK_V`.
    check_until_ms: Option<u32>,
    recheck: bool,
}

/// The low-voltage check before re-arming after a read-back fault: its voltage (V) and
/// length (ms). Every channel is driven to it, whatever its target (a target of 0 V too: a
/// short that stays draws its current there, before any `volt`), at no less than
/// [`LOW_CHECK_SLEW_V_PER_S`].
pub const LOW_CHECK_V: f32 = 200.0;
#[cfg(not(m3))]
pub const LOW_CHECK_MS: u32 = 300;
/// The check's least slew, V/s (the default slew: 100 ms to its voltage, 0.15 µA of charge
/// into the card's stack; under a slow slew, 100 V/s, a 1 MΩ short drew 15 µA at the check's
/// end, under the 30 µA trip).
#[cfg(not(m3))]
pub const LOW_CHECK_SLEW_V_PER_S: f32 = 2000.0;

#[cfg(not(m3))]
impl Sensing {
    fn new() -> Self {
        Sensing {
            present: false,
            guard_on: true,
            est: [sense::Estimator::new(); HV_CHANNELS],
            watch: [watch::Watch::new(); HV_CHANNELS],
            guard: [watch::ThicknessGuard::new(); HV_CHANNELS],
            vloop: [hv_loop::VoltageLoop::new(); HV_CHANNELS],
            cal: [sense::MonitorCal::NOMINAL; HV_CHANNELS],
            c0_pf: [crate::board::BOARD_STACK_C0_PF; HV_CHANNELS],
            drive: [0.0; HV_CHANNELS],
            ask: [hv_loop::Ask::ZERO; HV_CHANNELS],
            ripple_ms: [0; HV_CHANNELS],
            seen_windows: [0; HV_CHANNELS],
            view: SenseView {
                volts: [0.0; HV_CHANNELS],
                current_ua: [0.0; HV_CHANNELS],
                stack_ratio: [f32::NAN; HV_CHANNELS],
                ceiling_v: [0.0; HV_CHANNELS],
                disagreed: [false; HV_CHANNELS],
            },
            check_until_ms: None,
            recheck: false,
        }
    }
}

/// The watchdog is fed only when the command side checked in at most this long ago, ms. The
/// longest command (a first armed `pose`, docs/inverse-cost.md) stays far inside; a stuck
/// solve or console stops the feed and the IWDG (1 s) resets the board.
pub const CHECKIN_BOUND_MS: u32 = 250;

/// What the command side asks of the outputs.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Setpoints {
    /// Numbered by the command side; the view reports the last one taken.
    pub seq: u32,
    /// The stop count the command side had seen when it planned these: a stop since then
    /// makes them stale, and they are dropped.
    pub epoch: u32,
    /// HV enable wanted. False with the enable up: ramp to 0, then drop it (disarm).
    pub armed: bool,
    /// HV targets, V (each finite, >= 0, inside the ceiling: else refused).
    pub target_v: [f32; HV_CHANNELS],
    /// Servo duty holding the tension at the targets; reached as the voltages arrive.
    pub servo_duty: u16,
    /// Servo duty with the cable released (where `stop` sends it).
    pub servo_released: u16,
    /// The command side's ceiling per channel, as a duty (the core caps it further).
    pub duty_ceiling: [u16; HV_CHANNELS],
    /// HV slew, V/s.
    pub slew: f32,
    /// Shaped actuation: each channel drives the voltage that gives its target's equilibrium
    /// thickness now (above the target's voltage while the film creeps), never thinner than
    /// the target's thickness. False: plain slew to the target.
    pub shaped: bool,
}

/// What the core reports back.
// same shape as the model's `StackLaw` (a documented field list): unrelated data
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct View {
    /// Last setpoints taken.
    pub seq: u32,
    /// Stops so far.
    pub epoch: u32,
    pub volts: [f32; HV_CHANNELS],
    pub duty: [u16; HV_CHANNELS],
    pub enable: bool,
    pub servo_duty: u16,
    pub fault: Latched,
    /// The channel whose read-back latched the fault (0-based), if one did.
    pub fault_ch: Option<u8>,
    /// Locked out for good ([`Control::lock_out`]): never arms.
    pub locked_out: bool,
    /// Ticks since start, ms.
    pub now_ms: u32,
    /// Each stack's predicted thickness stretch now, s = z / z0 (1 at rest).
    pub stack_ratio: [f32; HV_CHANNELS],
    /// The read-back, on a board that has one (never on the Cortex-M3 image).
    #[cfg(not(m3))]
    pub sense: Option<SenseView>,
    /// The plant's trip latency (injection to the enable low), worst so far, µs: boards
    /// with a plant only.
    pub trip_max_us: Option<u32>,
    /// The plant's truth per channel and its film's G_eq (kPa): boards with a plant only.
    #[cfg(not(feature = "hw"))]
    pub plant: Option<PlantView>,
}

/// The refusal of the HV writer (`Control::write_hv_duty_checked`).
#[derive(Debug, PartialEq, Eq, Clone, Copy)]
pub struct HvRefused;

/// Control duty that makes the HV module output `v` volts, from the compiled calibration
/// (duty% = zero + (100 - zero) v / full scale), rounded down; 0 for NaN or v <= 0.
pub fn hv_duty_for(v: f32, max_duty: u16) -> u16 {
    let z = HV_ZERO_DUTY_PCT / 100.0;
    let d = (z + (1.0 - z) * (v / HV_FULL_SCALE_V)) * max_duty as f32;
    if !(d > 0.0) || !(v > 0.0) {
        0
    } else if d >= max_duty as f32 {
        max_duty
    } else {
        d as u16
    }
}

/// The hard duty cap of the image: the duty of [`HV_LIMIT_V`]. No parameter moves it.
pub fn hv_duty_cap(max_duty: u16) -> u16 {
    hv_duty_for(HV_LIMIT_V, max_duty)
}

/// The control core on a board `B`.
pub struct Control<B: Board> {
    board: B,
    hv_max: [u16; HV_CHANNELS],
    /// Targets' ceiling per channel: min(compiled cap, the board's hold ceiling, the command
    /// side's ceiling), as a duty.
    ceiling: [u16; HV_CHANNELS],
    /// The writer's refusal threshold per channel: the targets' ceiling (plain) or the
    /// compiled cap (shaped actuation drives above the target; the stack's guard bounds it).
    write_ceiling: [u16; HV_CHANNELS],
    /// The stacks in time (None: the board constants gave no law; never arms).
    stacks: Option<Stacks>,
    shaped: bool,
    /// Each channel's floor: `s_hold` (plain) or its target's equilibrium ratio (shaped).
    s_floor: [f32; HV_CHANNELS],
    volts: [f32; HV_CHANNELS],
    target: [f32; HV_CHANNELS],
    duty: [u16; HV_CHANNELS],
    slew: f32,
    enable: bool,
    ramping_down: bool,
    /// Servo: from where and to where it moves as the voltages go from `v_from` to `target`.
    servo_from: u16,
    servo_to: u16,
    servo_duty: u16,
    servo_released: u16,
    v_from: [f32; HV_CHANNELS],
    fault: Option<Fault>,
    /// The channel whose read-back latched `fault`, if one did.
    fault_ch: Option<u8>,
    /// Never arm (e.g. the emulator image on a real chip): the fault it reports, for good.
    lockout: Option<Fault>,
    seq: u32,
    epoch: u32,
    now_ms: u32,
    /// The read-back (`present` false: a board without one, open loop).
    #[cfg(not(m3))]
    sensing: Sensing,
    /// The channel's ceiling in force as a voltage: the writer's ceiling's.
    #[cfg(not(m3))]
    write_ceiling_v: [f32; HV_CHANNELS],
    /// The Cortex-M3 image's read-back: its hard checks in integers ([`trip`]).
    #[cfg(m3)]
    code_scale: trip::CodeScale,
    #[cfg(m3)]
    code_watch: [trip::CodeWatch; HV_CHANNELS],
    trip_max_us: Option<u32>,
    #[cfg(not(feature = "hw"))]
    plant_view: Option<PlantView>,
}

/// The voltage a duty gives through the compiled calibration (`hv_duty_for`'s inverse).
pub fn hv_volts_of_duty(duty: u16, max_duty: u16) -> f32 {
    let z = HV_ZERO_DUTY_PCT / 100.0;
    let f = duty as f32 / max_duty.max(1) as f32;
    if f > z {
        (f - z) / (1.0 - z) * HV_FULL_SCALE_V
    } else {
        0.0
    }
}

/// What one control tick's parts cost, in the caller's clock counts (`Control::tick_timed`).
#[derive(Clone, Copy, Debug, Default, PartialEq)]
pub struct TickCost {
    /// The longest stack step of a channel (goal, slew, guard, thickness, relaxation).
    pub stack_step: u32,
    /// The read-back's own work: the estimate, the checks, the guard and the voltage loop
    /// (0 on the M3 image, which has none).
    pub read_back: u32,
    /// The board's read-back source: the ADC's averages; on the emulator image, its plant's
    /// step (no part of the firmware's cost on a board).
    pub sense_source: u32,
}

impl<B: Board> Control<B> {
    /// Take the board: enable low, every HV duty 0, servo at `servo_released`. The ceilings
    /// start at 0 (nothing above 0 V until the command side sends its ceilings).
    pub fn new(board: B, servo_released: u16, slew: f32) -> Self {
        let stacks = Stacks::board();
        let s_hold = stacks.as_ref().map(|s| s.s_hold()).unwrap_or(1.0);
        let mut c = Control {
            board,
            hv_max: [0; HV_CHANNELS],
            ceiling: [0; HV_CHANNELS],
            write_ceiling: [0; HV_CHANNELS],
            stacks,
            shaped: false,
            s_floor: [s_hold; HV_CHANNELS],
            volts: [0.0; HV_CHANNELS],
            target: [0.0; HV_CHANNELS],
            duty: [0; HV_CHANNELS],
            slew,
            enable: false,
            ramping_down: false,
            servo_from: servo_released,
            servo_to: servo_released,
            servo_duty: servo_released,
            servo_released,
            v_from: [0.0; HV_CHANNELS],
            fault: None,
            fault_ch: None,
            lockout: None,
            seq: 0,
            epoch: 0,
            now_ms: 0,
            #[cfg(not(m3))]
            sensing: Sensing::new(),
            #[cfg(not(m3))]
            write_ceiling_v: [0.0; HV_CHANNELS],
            #[cfg(m3)]
            code_scale: trip::CodeScale::new(0),
            #[cfg(m3)]
            code_watch: [trip::CodeWatch::new(); HV_CHANNELS],
            trip_max_us: None,
            #[cfg(not(feature = "hw"))]
            plant_view: None,
        };
        for ch in 0..HV_CHANNELS {
            c.hv_max[ch] = c.board.hv(ch).max_duty_cycle();
        }
        // one scale: the three HV PWMs are one timer's (TIM4)
        #[cfg(m3)]
        {
            c.code_scale = trip::CodeScale::new(c.hv_max[0]);
        }
        c.hv_off_now();
        c.write_servo(servo_released);
        if c.stacks.is_none() {
            c.lock_out(Fault::BoardCard);
        }
        // a board with a read-back says so from the start (one sample taken, at 0 V)
        #[cfg(not(m3))]
        {
            c.sensing.present = c.board.hv_sense().is_some();
        }
        #[cfg(not(feature = "hw"))]
        c.read_plant();
        c
    }

    pub fn board(&self) -> &B {
        &self.board
    }
    #[cfg(feature = "sim")]
    pub fn board_mut(&mut self) -> &mut B {
        &mut self.board
    }
    /// Full-scale duty of each HV PWM.
    pub fn hv_max(&self) -> [u16; HV_CHANNELS] {
        self.hv_max
    }
    pub fn view(&self) -> View {
        View {
            seq: self.seq,
            epoch: self.epoch,
            volts: self.volts,
            duty: self.duty,
            enable: self.enable,
            servo_duty: self.servo_duty,
            fault: Latched(self.fault),
            fault_ch: self.fault_ch,
            locked_out: self.lockout.is_some(),
            now_ms: self.now_ms,
            stack_ratio: self.stacks.as_ref().map(|s| s.ratios()).unwrap_or([1.0; HV_CHANNELS]),
            #[cfg(not(m3))]
            sense: self.sensing.present.then_some(self.sensing.view),
            trip_max_us: self.trip_max_us,
            #[cfg(not(feature = "hw"))]
            plant: self.plant_view,
        }
    }

    /// The board's hold ceiling, V (0 without a law): no target passes it.
    pub fn hold_ceiling_v(&self) -> f32 {
        self.stacks.as_ref().map(|s| s.hold_ceiling_v()).unwrap_or(0.0)
    }
    /// The thinnest a held voltage ever gets: the invariant's floor.
    pub fn s_hold(&self) -> f32 {
        self.stacks.as_ref().map(|s| s.s_hold()).unwrap_or(1.0)
    }
    /// The HV writer's refusal threshold per channel, as a duty.
    pub fn duty_ceiling_now(&self) -> [u16; HV_CHANNELS] {
        self.write_ceiling
    }

    /// The single HV writer called directly: tests only (feature `hv-door`), for its refusals.
    #[cfg(feature = "hv-door")]
    pub fn write_hv_duty(&mut self, ch: usize, duty: u16) -> Result<(), HvRefused> {
        self.write_hv_duty_checked(ch, duty)
    }

    /// The one function that writes an HV duty. Refuses (writes nothing, latches the fault
    /// `hv-refused`) a duty above the channel's ceiling (the targets' ceiling; in shaped
    /// actuation the compiled cap) or the image's hard cap.
    fn write_hv_duty_checked(&mut self, ch: usize, duty: u16) -> Result<(), HvRefused> {
        if ch >= HV_CHANNELS || duty > self.write_ceiling[ch] || duty > hv_duty_cap(self.hv_max[ch]) {
            self.fault = Some(Fault::HvRefused);
            return Err(HvRefused);
        }
        if self.board.hv(ch).set_duty_cycle(duty).is_err() {
            self.fault = Some(Fault::Pwm);
            return Err(HvRefused);
        }
        self.duty[ch] = duty;
        Ok(())
    }

    fn set_enable(&mut self, on: bool) {
        let r = if on { self.board.hv_enable().set_high() } else { self.board.hv_enable().set_low() };
        if r.is_err() {
            self.fault = Some(Fault::Enable);
        }
        self.enable = on && r.is_ok();
    }

    fn write_servo(&mut self, duty: u16) {
        if self.board.servo().set_duty_cycle(duty).is_err() {
            self.fault = Some(Fault::Pwm);
        }
        self.servo_duty = duty;
    }

    /// HV off at once: enable low, every duty 0, values and targets 0.
    fn hv_off_now(&mut self) {
        self.set_enable(false);
        for ch in 0..HV_CHANNELS {
            let _ = self.write_hv_duty_checked(ch, 0);
        }
        self.volts = [0.0; HV_CHANNELS];
        self.target = [0.0; HV_CHANNELS];
        self.v_from = [0.0; HV_CHANNELS];
        self.s_floor = [self.s_hold(); HV_CHANNELS];
        self.ramping_down = false;
    }

    /// Emergency stop: HV off at once, cable released, a new epoch (setpoints planned before
    /// it are dropped). Clears a latched fault.
    pub fn stop(&mut self) {
        self.hv_off_now();
        #[cfg(not(m3))]
        {
            let sn = &mut self.sensing;
            let recheck = sn.recheck || matches!(self.fault, Some(f) if f.is_read_back());
            sn.watch = [watch::Watch::new(); HV_CHANNELS];
            sn.guard = [watch::ThicknessGuard::new(); HV_CHANNELS];
            sn.vloop = [hv_loop::VoltageLoop::new(); HV_CHANNELS];
            sn.drive = [0.0; HV_CHANNELS];
            sn.ask = [hv_loop::Ask::ZERO; HV_CHANNELS];
            sn.ripple_ms = [0; HV_CHANNELS];
            sn.check_until_ms = None;
            sn.recheck = recheck;
        }
        #[cfg(m3)]
        {
            self.code_watch = [trip::CodeWatch::new(); HV_CHANNELS];
        }
        self.fault_ch = None;
        self.servo_from = self.servo_released;
        self.servo_to = self.servo_released;
        self.write_servo(self.servo_released);
        self.epoch = self.epoch.wrapping_add(1);
        self.fault = self.lockout;
    }

    /// Never arm from now on; `reason` is the fault reported (a stop does not clear it).
    pub fn lock_out(&mut self, reason: Fault) {
        self.lockout = Some(reason);
        self.fault_stop(reason);
    }

    /// A fault stop: as [`Control::stop`], the fault stays latched, and so do the thickness
    /// guards' lowered ceilings (`vceil`, `film_check`: what the guard had found when the fault
    /// cut) until the `stop` that clears the fault.
    fn fault_stop(&mut self, f: Fault) {
        #[cfg(not(m3))]
        let guard = self.sensing.guard;
        self.stop();
        #[cfg(not(m3))]
        {
            self.sensing.guard = guard;
        }
        self.fault = Some(f);
    }

    /// Take the command side's setpoints. Dropped (false) when a stop came after they were
    /// planned. A target that is not finite, negative, past the board's hold ceiling or past
    /// the command side's ceiling is refused: fault stop (the command side checks first, so
    /// this is a second line).
    pub fn apply(&mut self, sp: &Setpoints) -> bool {
        if sp.epoch != self.epoch {
            return false;
        }
        self.seq = sp.seq;
        let hold = self.hold_ceiling_v();
        for ch in 0..HV_CHANNELS {
            let cap = hv_duty_cap(self.hv_max[ch]);
            self.ceiling[ch] = sp.duty_ceiling[ch].min(cap).min(hv_duty_for(hold, self.hv_max[ch]));
            self.write_ceiling[ch] = if sp.shaped { cap } else { self.ceiling[ch] };
            #[cfg(not(m3))]
            {
                self.write_ceiling_v[ch] = hv_volts_of_duty(self.write_ceiling[ch], self.hv_max[ch]);
            }
        }
        if sp.slew > 0.0 && sp.slew <= 1e6 {
            self.slew = sp.slew;
        }
        self.servo_released = sp.servo_released;
        // a latched fault takes no armed targets until `stop` (the enable stays low, and so
        // does every duty)
        if sp.armed && self.lockout.is_none() && self.fault.is_none() {
            let mut floor = [1.0f32; HV_CHANNELS];
            for ch in 0..HV_CHANNELS {
                let t = sp.target_v[ch];
                if !((0.0..=HV_LIMIT_V).contains(&t) && t <= hold) || hv_duty_for(t, self.hv_max[ch]) > self.ceiling[ch] {
                    self.fault_stop(Fault::HvRefused);
                    return true;
                }
                match self.stacks.as_ref().and_then(|s| s.floor(t, sp.shaped)) {
                    Some(f) => floor[ch] = f,
                    None => {
                        self.fault_stop(Fault::HvRefused);
                        return true;
                    }
                }
            }
            self.s_floor = floor;
            if self.fault.is_none() && !self.enable {
                self.set_enable(true);
                #[cfg(not(m3))]
                {
                    let sn = &mut self.sensing;
                    if core::mem::take(&mut sn.recheck) {
                        sn.check_until_ms = Some(self.now_ms.wrapping_add(LOW_CHECK_MS));
                    }
                }
            }
            self.ramping_down = false;
            self.target = sp.target_v;
        } else {
            self.target = [0.0; HV_CHANNELS];
            self.ramping_down = self.enable;
            self.s_floor = [self.s_hold(); HV_CHANNELS];
            // a disarm ends the low-voltage check unfinished: the next arm runs it again
            #[cfg(not(m3))]
            {
                let sn = &mut self.sensing;
                sn.recheck |= sn.check_until_ms.take().is_some();
            }
        }
        self.shaped = sp.shaped;
        self.v_from = self.volts;
        self.servo_from = self.servo_duty;
        self.servo_to = sp.servo_duty;
        self.follow_servo();
        self.finish_ramp_down();
        true
    }

    /// The servo between `servo_from` and `servo_to` in proportion to how far the slowest
    /// channel has come from `v_from` to its target (at once when no channel moves).
    fn follow_servo(&mut self) {
        let mut progress = 1.0f32;
        for ch in 0..HV_CHANNELS {
            let span = self.target[ch] - self.v_from[ch];
            if span != 0.0 {
                let p = (self.volts[ch] - self.v_from[ch]) / span;
                progress = progress.min(if p >= 0.0 { p } else { 0.0 });
            }
        }
        let (a, b) = (self.servo_from as f32, self.servo_to as f32);
        let d = a + (b - a) * progress;
        let d = if progress >= 1.0 { self.servo_to } else { (d + 0.5) as u16 };
        if d != self.servo_duty {
            self.write_servo(d);
        }
    }

    fn finish_ramp_down(&mut self) {
        #[cfg(not(m3))]
        let asked_zero = self.sensing.vloop.iter().all(|l| l.asked_v() == 0.0);
        #[cfg(m3)]
        let asked_zero = true;
        if self.ramping_down && asked_zero && self.volts.iter().all(|&v| v == 0.0) {
            for ch in 0..HV_CHANNELS {
                let _ = self.write_hv_duty_checked(ch, 0);
            }
            self.set_enable(false);
            self.ramping_down = false;
        }
    }

    /// One 1 ms control tick, as [`Control::tick_timed`] without the clock.
    pub fn tick(&mut self, last_checkin_ms: u32) {
        let _ = self.tick_timed(last_checkin_ms, || 0);
    }

    /// One 1 ms control tick. Each channel steps ([`Stacks::step`]): its value moves at most
    /// `slew` x 1 ms toward its goal (the target; in shaped actuation the voltage that holds
    /// the film at the target's thickness now, capped by the supply), the guard
    /// `v <= voltage_bound_now(state, s_floor)`, the thickness, the relaxation (after a stop
    /// too, at 0 V: the film recovers in time); the duty of the guarded value is written. Then
    /// the servo follows; a disarm ramp that reached 0 drops the enable; the watchdog is fed if
    /// the command side checked in at `last_checkin_ms` within [`CHECKIN_BOUND_MS`]. Returns
    /// what the tick's parts cost, in `clock` counts (`clock` runs forward within a tick; a
    /// reading that went back, a wrap, spans 0, never 2^32).
    pub fn tick_timed(&mut self, last_checkin_ms: u32, clock: fn() -> u32) -> TickCost {
        self.now_ms = self.now_ms.wrapping_add(1);
        let mut cost = TickCost::default();
        {
            let t0 = clock();
            cost.sense_source = self.read_back(clock);
            cost.read_back = clock().saturating_sub(t0).saturating_sub(cost.sense_source);
        }
        let step = self.slew_now() * 0.001;
        let mut worst = 0u32;
        #[cfg(not(m3))]
        let hold = self.hold_ceiling_v();
        for ch in 0..HV_CHANNELS {
            let Some(stacks) = self.stacks.as_mut() else { break };
            let v = self.volts[ch];
            #[allow(unused_mut)]
            let (mut t, mut v_cap) = (self.target[ch], HV_MAX_V);
            #[cfg(not(m3))]
            if self.sensing.present {
                let sn = &self.sensing;
                // the thickness guard's ceiling (a shaped drive no higher either), and the
                // low-voltage check's
                // a shaped drive's overdrive stays under the hold ceiling: past it the film's
                // response is the card's guess, which the read-back checks only after it
                let ceil = sn.view.ceiling_v[ch];
                v_cap = ceil.min(hold);
                t = t.min(ceil);
                if sn.check_until_ms.is_some() && self.enable {
                    // the check's voltage on every channel, whatever its target (under the
                    // channel's ceiling, exclusive; armed only: a disarm ends the check)
                    t = LOW_CHECK_V.min(ceil).min(self.write_ceiling_v[ch] * (1.0 - 8.0 * f32::EPSILON));
                    v_cap = LOW_CHECK_V;
                }
            }
            let t0 = clock();
            let applied = stacks.step(ch, v, t, self.s_floor[ch], self.shaped, step, v_cap);
            worst = worst.max(clock().saturating_sub(t0));
            // a fault stop zeroes every channel; the later ones still step (at 0 V)
            let nv = match applied {
                Ok(nv) if nv >= 0.0 => nv,
                _ => {
                    self.fault_stop(Fault::HvModel);
                    continue;
                }
            };
            #[cfg(not(m3))]
            let d = {
                let t0 = clock();
                // the ceiling in force, for the duty as for the measured voltage: a shaped
                // drive's guarded value is its bound itself, a plain one's the hold ceiling; both
                // within the sensed ceiling at once (a monitor reading low never lifts the true
                // voltage past it)
                let in_force = if self.shaped { nv.min(v_cap) } else { v_cap.min(hold) };
                let d = self.loop_duty(ch, nv, in_force);
                cost.read_back = cost.read_back.wrapping_add(clock().saturating_sub(t0));
                d
            };
            #[cfg(m3)]
            let d = hv_duty_for(nv, self.hv_max[ch]);
            if d != self.duty[ch] && self.write_hv_duty_checked(ch, d).is_err() {
                let f = self.fault.unwrap_or(Fault::HvRefused);
                self.fault_stop(f);
                continue;
            }
            self.volts[ch] = nv;
        }
        self.follow_servo();
        self.finish_ramp_down();
        if self.now_ms.wrapping_sub(last_checkin_ms) <= CHECKIN_BOUND_MS {
            self.board.feed_watchdog();
        }
        cost.stack_step = worst;
        cost
    }

    pub fn now_ms(&self) -> u32 {
        self.now_ms
    }

    /// The thickness guard on or off (tests only, feature `hv-door`: the guard shown to be
    /// what holds a soft film). Takes effect from the next window.
    #[cfg(all(feature = "hv-door", not(m3)))]
    pub fn set_thickness_guard(&mut self, on: bool) {
        self.sensing.guard_on = on;
    }

    /// The model's film creeps `k` times faster than the card's (tests only, feature
    /// `hv-door`: beside a plant film as fast, `Stacks::set_time_scale`). False: refused.
    #[cfg(all(feature = "hv-door", not(m3)))]
    pub fn set_film_time_scale(&mut self, k: f32) -> bool {
        self.stacks.as_mut().is_some_and(|s| s.set_time_scale(k))
    }

    /// The read-back's stored calibration (the command side's `cal vmon|c0`, the boot's
    /// record): a monitor that would read low (`MonitorCal::checked`) or a C0 out of range
    /// (half to twice the board's) is not taken, that channel keeps what it had.
    #[cfg(not(m3))]
    pub fn set_sense_cal(&mut self, monitor: [sense::MonitorCal; HV_CHANNELS], c0_pf: [f32; HV_CHANNELS]) {
        let c0 = crate::board::BOARD_STACK_C0_PF;
        for ch in 0..HV_CHANNELS {
            if let Some(m) = sense::MonitorCal::checked(monitor[ch].gain, monitor[ch].offset_v) {
                self.sensing.cal[ch] = m;
            }
            if c0_pf[ch] >= 0.5 * c0 && c0_pf[ch] <= 2.0 * c0 {
                self.sensing.c0_pf[ch] = c0_pf[ch];
            }
        }
    }

    /// The plant's truth into the view (boards with a plant).
    #[cfg(not(feature = "hw"))]
    fn read_plant(&mut self) {
        if let Some(p) = self.board.plant() {
            self.trip_max_us = Some(p.trip_max_us);
            let mut pv = PlantView { volts: [0.0; HV_CHANNELS], current_ua: [0.0; HV_CHANNELS], s: [1.0; HV_CHANNELS], film_kpa: p.film_kpa() };
            for (ch, t) in p.truth().iter().enumerate() {
                pv.volts[ch] = t.volts;
                pv.current_ua[ch] = t.current_ua;
                pv.s[ch] = t.s;
            }
            self.plant_view = Some(pv);
        }
    }

    /// The plant's test console: a change to the board's plant (none without one).
    #[cfg(not(feature = "hw"))]
    pub fn plant_request(&mut self, req: PlantRequest) {
        if let Some(p) = self.board.plant() {
            let _ = match req {
                PlantRequest::Film { g_eq_kpa, time_scale } => p.set_film(g_eq_kpa, time_scale),
                PlantRequest::Inject(ch, what) => p.inject(ch, what),
            };
        }
    }

    /// The duty of a guarded value `nv`: open loop without a read-back; with one, the hold
    /// ripple below `nv` once it is held, and the voltage loop, clamped to the open-loop duty of
    /// the ceiling in force `in_force_v` and to the channel's duty ceiling (the loop can ask no
    /// more than the open loop could: a module at its datasheet gain stays under the ceiling
    /// whatever the monitor reads).
    #[cfg(not(m3))]
    fn loop_duty(&mut self, ch: usize, nv: f32, in_force_v: f32) -> u16 {
        let max = self.hv_max[ch];
        let limit = self.write_ceiling[ch];
        if !self.sensing.present {
            return hv_duty_for(nv, max);
        }
        let slew_step = self.slew_now() * 0.001;
        let sn = &mut self.sensing;
        // steady (held, or a shaped or guarded voltage that creeps): the ripple measures it
        let held = nv > sense::RIPPLE_MIN_V && (nv - self.volts[ch]).abs() < 1.0 && self.enable;
        sn.ripple_ms[ch] = if held { sn.ripple_ms[ch].wrapping_add(1).max(1) } else { 0 };
        let ripple = if held { sense::ripple_v(sn.ripple_ms[ch]) } else { 0.0 };
        // the loop asks no more than the open loop could: the ceiling in force a few ulps
        // under it (the f32 hold ceiling, 5,400.0, rounds up from the card's 5,399.9999 V, and
        // its duty would be a count past that), within the channel's ceiling; its top is the
        // ripple below that (a loop pinned at its top still swings the ripple, so the film is
        // still measured), followed at the slew
        let limit_v = self.write_ceiling_v[ch].min(in_force_v * (1.0 - 8.0 * f32::EPSILON));
        let drive = (nv - ripple).min(limit_v);
        sn.drive[ch] = drive;
        // held, the ripple swings at its own rate under a slower slew (it only lowers the ask)
        let max_step = if held { slew_step.max(sense::RIPPLE_STEP_V) } else { slew_step };
        let ask = sn.vloop[ch].step(drive, sn.view.volts[ch], limit_v - ripple, limit_v, max_step);
        sn.ask[ch] = ask;
        hv_duty_for(ask.volts, max).min(limit)
    }

    /// The slew in force, V/s: the command side's, and during the low-voltage check at least
    /// [`LOW_CHECK_SLEW_V_PER_S`].
    fn slew_now(&self) -> f32 {
        #[cfg(not(m3))]
        if self.sensing.present && self.sensing.check_until_ms.is_some() {
            return self.slew.max(LOW_CHECK_SLEW_V_PER_S);
        }
        self.slew
    }

    /// The tick's read-back: the analog watchdog's trip, each channel's reading, estimate,
    /// checks and thickness guard. A fault cuts the HV at once (latched until `stop`).
    #[cfg(not(m3))]
    fn read_back(&mut self, clock: fn() -> u32) -> u32 {
        let t0 = clock();
        let Some(hs) = self.board.hv_sense() else { return 0 };
        #[cfg(not(feature = "hw"))]
        self.read_plant();
        let source = clock().saturating_sub(t0);
        let hold = self.hold_ceiling_v();
        let s_hold = self.s_hold();
        let sn = &mut self.sensing;
        sn.present = true;
        // the fault and the channel it came from
        let mut fault = None;
        if let Some(k) = hs.trip {
            fault = Some((Fault::Breakdown, k));
        }
        for ch in 0..HV_CHANNELS {
            let v = sense::volts_of_code(hs.v_code[ch], &sn.cal[ch]);
            let i = sense::microamps_of_code(hs.i_code[ch]);
            sn.view.volts[ch] = v;
            sn.view.current_ua[ch] = i;
            let c_ratio = self.stacks.as_ref().map_or(1.0, |st| st.incremental_capacitance_ratio(ch));
            sn.est[ch].tick(v, i, sn.ripple_ms[ch], c_ratio);
            let reading = watch::Reading { v, i_ua: i, v_code: hs.v_code[ch] };
            // the measured voltage's ceiling: the writer's, and with a read-back never above
            // the hold ceiling (a shaped drive stays under it: `tick_timed`); a guard's cut
            // is followed at the slew, so the hold ceiling, not the lowered one
            let over_ceiling_v = self.write_ceiling_v[ch].min(hold);
            if let Some(f) = sn.watch[ch].check(&reading, sn.drive[ch], &sn.ask[ch], over_ceiling_v, self.enable, &sn.est[ch]) {
                fault = fault.or(Some((f, ch as u8)));
            }
            let s_meas = sn.est[ch].thickness_ratio(sn.c0_pf[ch]);
            sn.view.stack_ratio[ch] = s_meas;
            let windows = sn.est[ch].windows();
            if windows != sn.seen_windows[ch] {
                sn.seen_windows[ch] = windows;
                // only a window that measured the film: a stale thickness is no news
                if let (Some(st), true, true) = (self.stacks.as_ref(), sn.guard_on, sn.est[ch].last_window_measured()) {
                    let s_model = st.ratios()[ch];
                    let (at_model, at_meas) = (st.equilibrium_voltage_at(s_model), st.equilibrium_voltage_at(s_meas));
                    sn.guard[ch].update(s_meas, s_model, s_hold, at_model, at_meas, sn.ripple_ms[ch], sn.est[ch].last_window_joint());
                }
            }
            sn.view.ceiling_v[ch] = sn.guard[ch].derate * hold;
            sn.view.disagreed[ch] = sn.guard[ch].disagreed;
        }
        if let Some(until) = sn.check_until_ms {
            if self.now_ms.wrapping_sub(until) < u32::MAX / 2 {
                sn.check_until_ms = None;
            }
        }
        self.latch_read_back(fault);
        source
    }

    /// The Cortex-M3 image's read-back: the analog watchdog's trip and each channel's hard
    /// checks in integers ([`trip::CodeWatch`]). A fault cuts the HV at once (latched until `stop`).
    #[cfg(m3)]
    fn read_back(&mut self, clock: fn() -> u32) -> u32 {
        let t0 = clock();
        let Some(hs) = self.board.hv_sense() else { return 0 };
        self.read_plant();
        let source = clock().saturating_sub(t0);
        let mut fault = hs.trip.map(|k| (Fault::Breakdown, k));
        for ch in 0..HV_CHANNELS {
            if let Some(f) = self.code_watch[ch].check(&self.code_scale, hs.v_code[ch], hs.i_code[ch], self.duty[ch], self.ceiling[ch], self.enable) {
                fault = fault.or(Some((f, ch as u8)));
            }
        }
        self.latch_read_back(fault);
        source
    }

    /// A read-back's fault and its channel: the HV cut, the fault latched (one already
    /// latched with the enable low stays).
    fn latch_read_back(&mut self, fault: Option<(Fault, u8)>) {
        if let Some((f, ch)) = fault {
            if self.fault.is_none() || self.enable {
                self.fault_stop(f);
                self.fault_ch = Some(ch);
            }
        }
    }
}
