//! The board build's cut on the HV outputs (src/cut.rs; the trip handler that sets it is
//! src/chip/hv_adc.rs, which no test here runs): the cut holds the enable low and every duty
//! at 0 from the trip until the tick that takes it (a `stop`, `arm` and `volt` in between
//! included), and a trip that lands between the duty's check and its store is zeroed after it.
use embedded_hal::digital::OutputPin;
use embedded_hal::pwm::SetDutyCycle;
use finger_fw::board::{Board, HvSense, HV_CHANNELS};
use finger_fw::cut::{CutEnable, CutPwm, TripCell};
use finger_fw::plant::Plant;
use finger_fw::sim::{SimPin, SimPwm};
use finger_fw::App;

/// The board build's outputs over the simulated pins, the plant behind the read-back, and
/// the trip cell the tick takes (as `hv_adc`'s `HvAdc::sense` does).
struct CutBoard {
    servo: SimPwm,
    hv: [CutPwm<SimPwm>; HV_CHANNELS],
    enable: CutEnable<SimPin>,
    plant: Plant,
    cell: &'static TripCell,
}

impl CutBoard {
    fn new(cell: &'static TripCell) -> Self {
        let pwm = SimPwm { duty: 0, max: 8_400, writes: 0 };
        CutBoard {
            servo: SimPwm { duty: 0, max: 40_000, writes: 0 },
            hv: [CutPwm::new(pwm, cell), CutPwm::new(pwm, cell), CutPwm::new(pwm, cell)],
            enable: CutEnable::new(SimPin::default(), cell),
            plant: Plant::new(1).unwrap(),
            cell,
        }
    }
    /// The trip handler on channel `ch`: the enable low and the duties 0 by register stores
    /// (past the wrappers), then the trip left for the tick.
    fn trip(&mut self, ch: u8) {
        let _ = self.enable.inner_mut().set_low();
        for h in self.hv.iter_mut() {
            let _ = h.inner_mut().set_duty_cycle(0);
        }
        self.cell.trip(ch);
    }
    /// What the pins drive: the enable and the duties.
    fn pins(&self) -> (bool, [u16; HV_CHANNELS]) {
        (self.enable.inner().high, [self.hv[0].inner().duty, self.hv[1].inner().duty, self.hv[2].inner().duty])
    }
}

impl Board for CutBoard {
    type Servo = SimPwm;
    type Hv = CutPwm<SimPwm>;
    type Enable = CutEnable<SimPin>;
    fn servo(&mut self) -> &mut SimPwm {
        &mut self.servo
    }
    fn hv(&mut self, ch: usize) -> &mut CutPwm<SimPwm> {
        &mut self.hv[ch]
    }
    fn hv_enable(&mut self) -> &mut CutEnable<SimPin> {
        &mut self.enable
    }
    fn feed_watchdog(&mut self) {}
    fn name(&self) -> &'static str {
        "cut"
    }
    fn hv_sense(&mut self) -> Option<HvSense> {
        let (enable, duty) = self.pins();
        let mut s = self.plant.tick(duty, self.hv[0].max_duty_cycle(), enable);
        s.trip = self.cell.take();
        Some(s)
    }
    fn plant(&mut self) -> Option<&mut Plant> {
        Some(&mut self.plant)
    }
}

fn run(app: &mut App<CutBoard>, line: &str) -> String {
    let mut out = String::new();
    app.execute(line.as_bytes(), &mut out);
    out
}

/// A trip, then `stop`, `arm` and `volt` before the next tick (the console's lines between two
/// ticks): the enable stays low and every duty 0, the tick takes the trip and latches
/// `breakdown`; only then does a fresh `stop`, `arm`, `volt` drive the HV again.
#[test]
fn the_cut_holds_across_stop_arm_and_volt_until_the_tick_takes_the_trip() {
    static CELL: TripCell = TripCell::new();
    let mut app = App::new(CutBoard::new(&CELL));
    for l in ["arm", "volt all 1000"] {
        assert!(run(&mut app, l).starts_with("ok"), "{l}");
    }
    let mut out = String::new();
    app.tick(20, &mut out);
    let (enable, duty) = app.board().pins();
    assert!(enable && duty.iter().all(|&d| d > 0), "driving before the trip: {enable} {duty:?}");

    app.board_mut().trip(1);
    for l in ["stop", "arm", "volt all 1000"] {
        assert!(run(&mut app, l).starts_with("ok"), "{l}");
        let (enable, duty) = app.board().pins();
        assert!(!enable && duty == [0; HV_CHANNELS], "after `{l}` under the cut: enable {enable}, duties {duty:?}");
    }
    assert!(CELL.cut(), "the cut stands until the tick");
    app.tick(1, &mut out);
    assert_eq!(app.fault(), Some("breakdown"), "the tick took the trip");
    assert!(!CELL.cut());
    let (enable, duty) = app.board().pins();
    assert!(!enable && duty == [0; HV_CHANNELS], "after the tick: {enable} {duty:?}");
    assert!(run(&mut app, "arm").starts_with("err"), "a latched breakdown refuses `arm` until `stop`");

    // the trip taken, the cut is over: a `stop` clears the fault and the HV drives again
    for l in ["stop", "arm", "volt all 1000"] {
        assert!(run(&mut app, l).starts_with("ok"), "{l}");
    }
    app.tick(20, &mut out);
    let (enable, duty) = app.board().pins();
    assert!(enable && duty.iter().all(|&d| d > 0), "after the fault's stop: {enable} {duty:?}");
}

/// A PWM whose store lands just after a trip: the handler zeroes the register between the
/// wrapper's check and the store (which then writes the duty over its zero).
struct RacyPwm {
    duty: u16,
    cell: &'static TripCell,
    trip_before_store: bool,
}

impl embedded_hal::pwm::ErrorType for RacyPwm {
    type Error = core::convert::Infallible;
}

impl SetDutyCycle for RacyPwm {
    fn max_duty_cycle(&self) -> u16 {
        8_400
    }
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Self::Error> {
        if core::mem::take(&mut self.trip_before_store) {
            self.cell.trip(0);
            self.duty = 0;
        }
        self.duty = duty;
        Ok(())
    }
}

/// The duty's store, then the cut checked again: a trip between the check and the store
/// leaves the duty 0, not the value written over the handler's zero.
#[test]
fn a_trip_between_the_check_and_the_store_leaves_duty_zero() {
    static CELL: TripCell = TripCell::new();
    for duty in [1u16, 2_000, 8_400] {
        CELL.take();
        let mut pwm = CutPwm::new(RacyPwm { duty: 0, cell: &CELL, trip_before_store: true }, &CELL);
        pwm.set_duty_cycle(duty).unwrap();
        assert_eq!(pwm.inner().duty, 0, "duty {duty}: a trip during the store");
        // no trip: the duty as written; under the cut: 0
        CELL.take();
        let mut pwm = CutPwm::new(RacyPwm { duty: 0, cell: &CELL, trip_before_store: false }, &CELL);
        pwm.set_duty_cycle(duty).unwrap();
        assert_eq!(pwm.inner().duty, duty);
        CELL.trip(2);
        pwm.set_duty_cycle(duty).unwrap();
        assert_eq!(pwm.inner().duty, 0, "duty {duty} under the cut");
    }
}
