//! The stored settings in QEMU (the F405 image; docs/firmware.md "Settings"): `param`, `cal`
//! and `save`, then the monitor's `system_reset`: after the banner the values read back are
//! the saved ones; `factory` brings the compiled defaults back; settings that raise the
//! ceiling are refused at `save`, and, forced into the store (QEMU's loader writes a record
//! built on the host into the store's RAM), refused at boot.
use finger_fw::app::config::record_of;
use finger_fw::flash_ram::{F405_BASE, FORMATTED, PAGE, PAGES};
use finger_fw::settings::{tag, ConfigStore, FlashStore, RECORD_MAX};
use host_tests::console::ok;
use host_tests::cut_flash::CutFlash;
use host_tests::image::image;
use host_tests::qemu::Qemu;
use host_tests::reply::val;

const CAL: &str = "1.5 2 1 1.25 0.5 0 2 -0.25";
const CAL_REPLY: &str = "ok cal=1.500000,2.000000,1.000000,1.250000,0.500000,0.000000,2.000000,-0.250000";
const CAL_DEFAULT: &str = "ok cal=1.540745,6.245597,1.066900,1.154625,0.718260,0.054631,5.254023,-1.756332";

#[test]
fn saved_settings_survive_system_reset_and_factory_restores_defaults() {
    let mut q = Qemu::boot(&format!("settings-{}", line!()));
    assert!(q.banner.contains(" config=empty "), "{}", q.banner);
    assert_eq!(ok(&mut q, "param slew 500"), "ok slew=500");
    ok(&mut q, "param servo_range 200");
    ok(&mut q, "param margin 0.5");
    assert_eq!(ok(&mut q, &format!("cal {CAL}")), CAL_REPLY);
    let saved = ok(&mut q, "save");
    assert!(saved.starts_with("ok saved=1 bytes="), "{saved}");
    let limits = ok(&mut q, "limits");

    q.system_reset();
    assert!(q.banner.contains(" config=loaded "), "{}", q.banner);
    assert_eq!(ok(&mut q, "param slew"), "ok slew=500");
    assert_eq!(ok(&mut q, "param servo_range"), "ok servo_range=200");
    assert_eq!(ok(&mut q, "param margin"), "ok margin=0.5");
    assert_eq!(ok(&mut q, "cal"), CAL_REPLY);
    assert_eq!(ok(&mut q, "limits"), limits);
    let c = ok(&mut q, "config");
    assert!(c.starts_with("ok store=saved saves=1 boot=loaded fault=none format=1"), "{c}");
    assert_eq!(val(&q.cmd("status"), "fault"), "none");

    // a second save counts on from the loaded one
    ok(&mut q, "param slew 700");
    assert!(ok(&mut q, "save").starts_with("ok saved=2 "));
    q.system_reset();
    assert_eq!(ok(&mut q, "param slew"), "ok slew=700");

    // factory: the compiled defaults now and after a reset
    assert!(q.cmd("arm").starts_with("ok"));
    assert!(q.cmd("factory").starts_with("err armed: "));
    ok(&mut q, "disarm");
    assert_eq!(ok(&mut q, "factory"), "ok factory=1 store=empty");
    assert_eq!(ok(&mut q, "param slew"), "ok slew=2000");
    assert_eq!(ok(&mut q, "cal"), CAL_DEFAULT);
    q.system_reset();
    assert!(q.banner.contains(" config=empty "), "{}", q.banner);
    assert_eq!(ok(&mut q, "param slew"), "ok slew=2000");
    assert_eq!(ok(&mut q, "param margin"), "ok margin=0.9");
    assert_eq!(ok(&mut q, "cal"), CAL_DEFAULT);

    // a setting that raises the ceiling is refused at save: the store stays as it was (the
    // board's film's hold ceiling binds, not the supply: a higher margin raises it)
    ok(&mut q, "param margin 0.99");
    let r = q.cmd("save");
    assert!(r.starts_with("err limit: save: these settings raise the model's ceiling"), "{r}");
    q.system_reset();
    assert!(q.banner.contains(" config=empty "), "{}", q.banner);
    assert_eq!(ok(&mut q, "param margin"), "ok margin=0.9");
}

#[test]
fn a_forced_store_that_raises_the_ceiling_is_refused_at_boot() {
    // the record `save` refuses (margin 0.99), built on the host into the store's pages
    let app = finger_fw::App::new(finger_fw::sim::SimBoard::default());
    let mut rec = record_of(app.finger(), app.fw_params(), 1);
    rec.values.iter_mut().find(|v| v.0 == tag(b'p', "margin")).unwrap().1 = 0.99;
    let mut bytes = [0u8; RECORD_MAX];
    let n = rec.encode(&mut bytes);
    let flash = CutFlash::<PAGE>::new(PAGES);
    FlashStore::new(flash.clone(), 0..(PAGES * PAGE) as u32).write(&bytes[..n]).unwrap();
    let mut blob = flash.bytes();
    blob.extend_from_slice(&FORMATTED.to_le_bytes());
    let path = std::env::temp_dir().join(format!("finger-settings-{}.bin", std::process::id()));
    std::fs::write(&path, &blob).unwrap();
    let loader = format!("loader,file={},addr={F405_BASE:#x},force-raw=on", path.display());
    let mut q = Qemu::boot_with(image(), &format!("settings-{}", line!()), &["-device", &loader]);
    let _ = std::fs::remove_file(&path);
    assert!(q.banner.contains(" config=rejected reason=ceiling defaults "), "{}", q.banner);
    assert_eq!(val(&q.cmd("status"), "fault"), "config-rejected");
    let c = q.cmd("config");
    assert!(c.contains(" boot=rejected reason=ceiling fault=config-rejected "), "{c}");
    assert_eq!(ok(&mut q, "param margin"), "ok margin=0.9");
    // the defaults' ceiling: the board's hold ceiling
    let vhold = val(&ok(&mut q, "material"), "vhold").to_owned();
    assert!(ok(&mut q, "limits").starts_with(&format!("ok vmax={vhold},{vhold},{vhold} ")));
    // a fresh save clears the fault
    assert!(ok(&mut q, "save").starts_with("ok saved=1 "));
    assert_eq!(val(&q.cmd("status"), "fault"), "none");
}
