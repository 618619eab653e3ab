//! Gravity's parameters at the console (issue 53) on the simulated board: `param grav`,
//! `grav_dir` and `rho_b` listed with their ranges and set like every model parameter; out of
//! range, not a number, or while armed refused, changing nothing; the board's finger hangs
//! straight down under standard gravity (`board::BOARD_GRAVITY`), `preset paper` has none;
//! `status` and `limits` show the orientation in force; a setting with gravity survives a
//! reset (`save`), and a record from before gravity keeps the board's.
use finger_fw::app::config::{record_of, Boot};
use finger_fw::board::{BOARD_GRAVITY, BOARD_GRAV_DIR_DEG, BOARD_GRAV_M_S2};
use finger_fw::settings::{tag, ConfigStore, FlashStore, Record, RECORD_MAX};
use finger_fw::sim::SimBoard;
use finger_fw::App;
use finger_model::Calibration;
use host_tests::console::{err, ok};
use host_tests::cut_flash::CutFlash;
use host_tests::reply::val;
use host_tests::sim_console::{cmd, feed_text};

const PAGE: usize = 1024;
const PAGES: usize = 3;
type Flash = CutFlash<PAGE>;

fn app() -> App<SimBoard> {
    App::new(SimBoard::default())
}

fn boot(flash: &Flash) -> App<SimBoard> {
    App::with_store(SimBoard::default(), Box::leak(Box::new(FlashStore::new(flash.clone(), 0..(PAGES * PAGE) as u32))))
}

/// The orientation `status` and `limits` report, each as (grav, grav_dir) text.
fn orientation(a: &mut App<SimBoard>) -> [(String, String); 2] {
    ["status", "limits"].map(|c| {
        let r = ok(a, c);
        (val(&r, "grav").to_string(), val(&r, "grav_dir").to_string())
    })
}

fn is(a: &mut App<SimBoard>, grav: &str, dir: &str) {
    let want = (grav.to_string(), dir.to_string());
    assert_eq!(orientation(a), [want.clone(), want]);
}

/// Everything a refused command must leave as it was: every parameter, `cal`, `limits`, a
/// solve and the status.
fn everything(a: &mut App<SimBoard>) -> String {
    ["param", "cal", "limits", "solve 0.5 800 400 0", "status"].iter().map(|l| feed_text(a, format!("{l}\n").as_bytes())).collect()
}

#[test]
fn the_boards_finger_hangs_straight_down_and_the_paper_has_no_gravity() {
    let mut a = app();
    assert!(BOARD_GRAVITY, "the board's default is gravity on (issue 53)");
    assert_eq!((BOARD_GRAV_M_S2, BOARD_GRAV_DIR_DEG), (finger_model::params::G_STANDARD, 0.0));
    is(&mut a, "9.81", "0");
    assert_eq!(ok(&mut a, "param grav"), "ok grav=9.81");
    assert_eq!(ok(&mut a, "param grav_dir"), "ok grav_dir=0");
    assert_eq!(ok(&mut a, "param rho_b"), "ok rho_b=1.19");
    // gravity keeps the board's FE calibration (computed without it)
    assert_eq!(*a.finger().calibration(), Calibration::model_md());
    assert_eq!(ok(&mut a, "preset paper"), "ok preset=paper");
    is(&mut a, "0", "0");
    assert_eq!(ok(&mut a, "preset default"), "ok preset=default");
    is(&mut a, "9.81", "0");
    assert_eq!(*a.finger().calibration(), Calibration::model_md());
}

#[test]
fn gravity_is_listed_set_and_shown() {
    let mut a = app();
    let list = feed_text(&mut a, b"param\n");
    for want in ["grav=9.81 (0..20 m/s2 (0: off))", "grav_dir=0 (-180..180 deg from +x toward +y)", "rho_b=1.19 (0..25 g/cm3)"] {
        assert!(list.lines().any(|l| l == want), "param lacks {want}:\n{list}");
    }
    let cal = ok(&mut a, "cal");
    for (line, reply, grav, dir) in [
        ("param grav_dir 90", "ok grav_dir=90", "9.81", "90"),
        ("param grav_dir -90", "ok grav_dir=-90", "9.81", "-90"),
        ("param grav_dir 180", "ok grav_dir=180", "9.81", "180"),
        ("param grav_dir -180", "ok grav_dir=-180", "9.81", "-180"),
        ("param grav 1.62", "ok grav=1.62", "1.62", "-180"),
        ("param grav 20", "ok grav=20", "20", "-180"),
        ("param grav 0", "ok grav=0", "0", "-180"),
    ] {
        assert_eq!(ok(&mut a, line), reply);
        is(&mut a, grav, dir);
        // the calibration stays (gravity is in KEEPS_CALIBRATION)
        assert_eq!(ok(&mut a, "cal"), cal, "{line}");
    }
    assert_eq!(ok(&mut a, "param rho_b 1.3"), "ok rho_b=1.3");
    assert_eq!(ok(&mut a, "param rho_b"), "ok rho_b=1.3");
    assert_eq!(ok(&mut a, "cal"), cal);
}

#[test]
fn bad_gravity_is_refused_and_changes_nothing() {
    let mut a = app();
    ok(&mut a, "param grav_dir 45");
    let before = everything(&mut a);
    for (line, code) in [
        ("param grav -0.1", "usage"),
        ("param grav 20.5", "usage"),
        ("param grav 1e30", "usage"),
        ("param grav_dir 180.5", "usage"),
        ("param grav_dir -181", "usage"),
        ("param grav_dir 360", "usage"),
        ("param rho_b -1", "usage"),
        ("param rho_b 26", "usage"),
        ("param grav nan", "bad-number"),
        ("param grav inf", "bad-number"),
        ("param grav_dir NaN", "bad-number"),
        ("param grav_dir -inf", "bad-number"),
        ("param rho_b nan", "bad-number"),
        ("param grav 9.81 0", "usage"),
    ] {
        let r = err(&mut a, line, code);
        if code == "usage" && !line.ends_with(" 0") {
            let name = line.split(' ').nth(1).unwrap();
            assert!(r.contains(name) && r.contains(".."), "{line}: the refusal names the parameter and its range: {r}");
        }
        assert_eq!(everything(&mut a), before, "{line} changed something");
    }
    // armed: refused, the orientation unchanged
    ok(&mut a, "arm");
    let armed = (cmd(&mut a, "status"), cmd(&mut a, "limits"));
    for line in ["param grav 0", "param grav_dir 90", "param rho_b 1.3", "param grav"] {
        let r = err(&mut a, line, "armed");
        assert!(r.contains("only while disarmed"), "{r}");
        assert_eq!((cmd(&mut a, "status"), cmd(&mut a, "limits")), armed, "{line}");
    }
    ok(&mut a, "disarm");
    ok(&mut a, "stop");
    is(&mut a, "9.81", "45");
}

#[test]
fn a_saved_orientation_survives_a_reset() {
    let flash = Flash::new(PAGES);
    let mut a = boot(&flash);
    assert_eq!(a.config_boot(), Boot::Empty);
    for l in ["param grav_dir -90", "param grav 5", "param rho_b 1.25"] {
        ok(&mut a, l);
    }
    assert!(ok(&mut a, "save").starts_with("ok saved=1"));
    let want = everything(&mut a);
    let mut b = boot(&flash);
    assert_eq!(b.config_boot(), Boot::Loaded);
    is(&mut b, "5", "-90");
    assert_eq!(ok(&mut b, "param rho_b"), "ok rho_b=1.25");
    assert_eq!(everything(&mut b), want);
    // `config` names each stored value that differs from the compiled defaults
    let c = feed_text(&mut b, b"config\n");
    for l in ["stored grav=5 default=9.81", "stored grav_dir=-90 default=0", "stored rho_b=1.25 default=1.19"] {
        assert!(c.lines().any(|x| x == l), "config lacks {l}:\n{c}");
    }
    // off (grav 0) is a setting too
    ok(&mut b, "param grav 0");
    ok(&mut b, "save");
    let mut c = boot(&flash);
    is(&mut c, "0", "-90");
    // factory: the board's orientation again
    assert_eq!(ok(&mut c, "factory"), "ok factory=1 store=empty");
    is(&mut c, "9.81", "0");
    is(&mut boot(&flash), "9.81", "0");
}

#[test]
fn a_record_from_before_gravity_keeps_the_boards_orientation() {
    // a record of this format written before gravity's parameters: none of their tags
    let a = {
        let mut a = app();
        ok(&mut a, "param slew 700");
        a
    };
    let mut rec: Record = record_of(a.finger(), a.fw_params(), 3);
    let grav = ["grav", "grav_dir", "rho_b"].map(|n| tag(b'p', n));
    let n = rec.values.len();
    rec.values.retain(|v| !grav.contains(&v.0));
    assert_eq!(rec.values.len(), n - 3);
    let mut buf = [0u8; RECORD_MAX];
    let len = rec.encode(&mut buf);
    let flash = Flash::new(PAGES);
    FlashStore::new(flash.clone(), 0..(PAGES * PAGE) as u32).write(&buf[..len]).unwrap();
    let mut b = boot(&flash);
    assert_eq!(b.config_boot(), Boot::Loaded);
    assert_eq!(ok(&mut b, "param slew"), "ok slew=700");
    is(&mut b, "9.81", "0");
    assert_eq!(ok(&mut b, "param rho_b"), "ok rho_b=1.19");
}
