//! The read-back's stored calibration (src/app/hv_cal.rs, `cal show|vmon|c0`): each refusal
//! (a monitor that reads low, a C0 out of range, armed, a bad number) changes nothing; a
//! calibration is saved with the settings, applied at boot, and a record holding a loosening
//! one is refused whole; the rule shown to be what holds the ceiling; a C0 that makes the
//! sensed film thicker raises nothing, one that makes it thinner lowers the ceiling.
use finger_fw::app::config::{record_of, Boot, Reject};
use finger_fw::app::hv_cal::SenseCal;
use finger_fw::control::sense::MonitorCal;
use finger_fw::plant::{Inject, Plant};
use finger_fw::settings::{tag, ConfigStore, FlashStore, RECORD_MAX};
use finger_fw::sim::SimBoard;
use finger_fw::App;
use host_tests::cut_flash::CutFlash;
use host_tests::plant_runs::{armed, run};
use host_tests::sim_console::cmd;

type Flash = CutFlash<1024>;

fn store_on(flash: &Flash) -> &'static mut FlashStore<Flash> {
    Box::leak(Box::new(FlashStore::new(flash.clone(), 0..3 * 1024)))
}

fn plant_app() -> App<SimBoard> {
    App::new(SimBoard::with_plant(Plant::new(3).unwrap()))
}

#[test]
fn each_refusal_changes_nothing() {
    let mut a = plant_app();
    let before = cmd(&mut a, "cal show");
    assert!(before.starts_with("ok vgain=1.0000,1.0000,1.0000 voff=0.0,0.0,0.0 c0_pf="), "{before}");
    for (line, code) in [
        ("cal vmon 1 0.95 0", "err limit"), // reads 5 % low
        ("cal vmon 2 1.0 -5", "err limit"), // an offset below 0
        ("cal vmon 3 1.5 0", "err limit"),  // past its range
        ("cal c0 1 10", "err usage"),       // far below the stack's
        ("cal c0 2 500", "err usage"),      // far above
        ("cal c0 4 68", "err usage"),       // no channel 4
        ("cal vmon 1 x 0", "err bad-number"),
        ("cal vmon 1", "err usage"),
    ] {
        let r = cmd(&mut a, line);
        assert!(r.starts_with(code), "{line} -> {r}");
        assert_eq!(cmd(&mut a, "cal show"), before, "{line} changed the calibration");
    }
    // armed: refused too
    assert!(cmd(&mut a, "arm").starts_with("ok"));
    let r = cmd(&mut a, "cal c0 1 70");
    assert!(r.starts_with("err armed"), "{r}");
    assert_eq!(cmd(&mut a, "cal show"), before);
    // the FE calibration's grammar is as before
    assert!(cmd(&mut a, "cal").starts_with("ok cal="));
}

#[test]
fn a_calibration_is_in_force_at_once_and_stored_and_applied_at_boot() {
    let flash = Flash::new(3);
    let mut a = App::with_store(SimBoard::with_plant(Plant::new(5).unwrap()), store_on(&flash));
    let r = cmd(&mut a, "cal vmon 2 1.05 12.5");
    assert!(r.starts_with("ok vgain=1.0000,1.0500,1.0000 voff=0.0,12.5,0.0"), "{r}");
    let r = cmd(&mut a, "cal c0 3 71.5");
    assert!(r.contains(",71.50"), "{r}");
    assert!(cmd(&mut a, "save").starts_with("ok saved="));
    // a fresh boot on the same flash: the calibration back, and in the core
    let mut b = App::with_store(SimBoard::with_plant(Plant::new(5).unwrap()), store_on(&flash));
    assert_eq!(b.config_boot(), Boot::Loaded);
    assert_eq!(cmd(&mut b, "cal show"), r);
    // the core reads channel 2 through its calibration: 0 V reads the offset
    b.tick(5, &mut String::new());
    let s = b.control().view().sense.expect("read-back");
    assert!((s.volts[1] - 12.5).abs() < 3.0 && s.volts[0].abs() < 3.0, "{:?}", s.volts);
    // factory: nominal again
    assert!(cmd(&mut b, "factory").starts_with("ok"));
    assert!(cmd(&mut b, "cal show").starts_with("ok vgain=1.0000,1.0000,1.0000 voff=0.0,0.0,0.0"));
}

#[test]
fn a_record_with_a_loosening_calibration_is_refused_whole() {
    for (name, v) in [("vgain1", 0.9f32), ("voff2", -20.0), ("c0_3", 1000.0)] {
        let flash = Flash::new(3);
        let a = App::new(SimBoard::default());
        let mut rec = record_of(a.finger(), a.fw_params(), 1);
        rec.values.push((tag(b'h', name), v)).unwrap();
        let mut buf = [0u8; RECORD_MAX];
        let n = rec.encode(&mut buf);
        store_on(&flash).write(&buf[..n]).unwrap();
        let mut b = App::with_store(SimBoard::with_plant(Plant::new(1).unwrap()), store_on(&flash));
        assert_eq!(b.config_boot(), Boot::Rejected(Reject::SenseCal), "{name}={v}");
        assert!(cmd(&mut b, "cal show").starts_with("ok vgain=1.0000,1.0000,1.0000 voff=0.0,0.0,0.0"));
        assert!(cmd(&mut b, "status").contains("fault=config-rejected"));
    }
}

/// A module 10 % strong held at the ceiling: with the monitor nominal (a low-reading
/// calibration refused, by the console and by the core), the loop holds the true voltage at
/// the command. With the rule switched off (the loop seeing what the refused gain 0.9 would
/// make it see: the plant's monitor reading 10 % low) the true voltage passes the ceiling.
#[test]
fn the_refused_monitor_calibration_is_what_holds_the_ceiling() {
    let held = |rule_on: bool| {
        let mut p = Plant::new(21).unwrap();
        for ch in 0..3 {
            p.inject(ch, Inject::Gain(1.1)).unwrap();
        }
        if !rule_on {
            p.set_parts(finger_fw::board::SENSE_STRAY_PF, 0.9);
        }
        let mut c = armed(p, [0.0; 3]);
        // the monitor alone: a low reading also reads the capacitance high, which the
        // thickness guard would answer by lowering the ceiling (a film that reads thin)
        c.set_thickness_guard(false);
        let hold = c.hold_ceiling_v();
        // the core refuses the low calibration itself too
        c.set_sense_cal([MonitorCal { gain: 0.9, offset_v: 0.0 }; 3], SenseCal::NOMINAL.c0_pf);
        c.apply(&host_tests::hv::setpoints(&c, [hold - 1.0; 3], false, 2000.0));
        let mut vmax: f32 = 0.0;
        for _ in 0..4400 {
            run(&mut c, 1);
            vmax = vmax.max(c.board().plant.as_ref().unwrap().truth()[0].volts);
        }
        (vmax, hold, c.view().fault.get())
    };
    let (v_on, hold, fault) = held(true);
    assert!(v_on <= hold * 1.01, "rule on: {v_on} V against the ceiling {hold} V");
    assert_eq!(fault, None);
    let (v_off, _, fault) = held(false);
    assert!(v_off > hold * 1.05, "rule off: {v_off} V should pass the ceiling {hold} V (fault {fault:?})");
}

/// A soft film (half the card's modulus) held at the ceiling: a C0 that makes the sensed film
/// thicker than the model's (twice the stack's) never raises the channel's ceiling past the
/// hold ceiling; a C0 that makes it thinner lowers it.
#[test]
fn a_c0_can_only_lower_the_ceiling() {
    let ceiling = |c0_factor: f32| {
        let mut p = Plant::new(8).unwrap();
        p.set_film(6.7, 10.0).unwrap();
        let mut c = armed(p, [0.0; 3]);
        let hold = c.hold_ceiling_v();
        c.set_sense_cal([MonitorCal::NOMINAL; 3], [finger_fw::board::BOARD_STACK_C0_PF * c0_factor; 3]);
        c.apply(&host_tests::hv::setpoints(&c, [hold - 1.0; 3], false, 2000.0));
        let mut top: f32 = 0.0;
        for _ in 0..100 {
            run(&mut c, 100);
            top = top.max(c.view().sense.unwrap().ceiling_v[0]);
        }
        (top, c.view().sense.unwrap().ceiling_v[0], hold)
    };
    let (top, _, hold) = ceiling(2.0);
    assert!(top <= hold, "a thicker sensed film raised the ceiling to {top} V past {hold} V");
    let (_, nominal_end, _) = ceiling(1.0);
    let (_, thin_end, _) = ceiling(0.8);
    assert!(thin_end < nominal_end, "a thinner sensed film: {thin_end} V, nominal C0: {nominal_end} V");
}
