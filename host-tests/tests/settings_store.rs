//! The stored settings (docs/firmware.md "Settings") on the simulated board over a flash whose
//! power can be cut after any byte written or erased (host_tests::cut_flash):
//! - a cut at every byte offset of a sequence of saves, and 10,000 random sequences of saves
//!   with random cuts: the next boot loads the complete old or the complete new record, and
//!   the board then answers exactly as one given those settings at the console;
//! - corrupted stores (random bytes, truncated and zeroed sectors, records with a valid
//!   checksum holding out-of-range values, a raised ceiling, unknown or repeated values, another
//!   format version) are refused whole: compiled defaults, `fault=config-rejected`;
//! - `save` refuses settings that raise the ceiling; `factory` erases.
use finger_fw::app::config::{default_finger, record_of, settings_of, Boot, Reject};
use finger_fw::settings::{tag, ConfigStore, FlashStore, FormatError, Record, StoreError, RECORD_MAX};
use finger_fw::sim::SimBoard;
use finger_fw::{App, FwParams};
use host_tests::cut_flash::CutFlash;
use host_tests::reply::val;
use host_tests::sim_console::{cmd, feed_text};

/// Small pages, so a few saves fill one and the map closes, migrates and erases pages.
const PAGE: usize = 1024;
const PAGES: usize = 3;
type Flash = CutFlash<PAGE>;

/// Settings a user can reach at the console (each list from the compiled defaults).
const SCRIPTS: &[&[&str]] = &[
    &[],
    &["param slew 500", "param servo_range 200", "cal 1.5 2 1 1.25 0.5 0 2 -0.25"],
    &["param margin 0.5", "param spool_r 12"],
    &["param l 30", "param a 6", "param servo_dir -1"],
    &["param e_b 15", "param nu_b 0.4", "param slew 4000"],
    &["param layers 0"],
    &["param t_min 1.2", "param e 4.4", "param b 9", "cal none"],
    &["param grav_dir 90", "param grav 3.5", "param rho_b 1.3"],
];

/// A deterministic generator for the random sequences (SplitMix64).
struct Rng(u64);
impl Rng {
    fn next(&mut self) -> u64 {
        self.0 = self.0.wrapping_add(0x9E37_79B9_7F4A_7C15);
        let mut z = self.0;
        z = (z ^ (z >> 30)).wrapping_mul(0xBF58_476D_1CE4_E5B9);
        z = (z ^ (z >> 27)).wrapping_mul(0x94D0_49BB_1331_11EB);
        z ^ (z >> 31)
    }
    fn below(&mut self, n: u64) -> u64 {
        self.next() % n
    }
}

fn store_on(flash: &Flash) -> &'static mut FlashStore<Flash> {
    Box::leak(Box::new(FlashStore::new(flash.clone(), 0..(PAGES * PAGE) as u32)))
}

/// A board booted on `flash` (a reset: a new store over the same bytes).
fn boot(flash: &Flash) -> App<SimBoard> {
    App::with_store(SimBoard::default(), store_on(flash))
}

/// A board without a store given `script` at the console.
fn typed(script: &[&str]) -> App<SimBoard> {
    let mut a = App::new(SimBoard::default());
    run(&mut a, script);
    a
}

fn run(a: &mut App<SimBoard>, script: &[&str]) {
    for l in script {
        let r = cmd(a, l);
        assert!(r.starts_with("ok"), "{l} -> {r}");
    }
}

/// The settings in force, as stored values (exact bits).
fn settings(a: &App<SimBoard>) -> Vec<(u16, u32)> {
    record_of(a.finger(), a.fw_params(), 0).values.iter().map(|&(t, v)| (t, v.to_bits())).collect()
}

/// What the board answers: parameters, calibration, ceilings, fmax, a solve, the status.
fn transcript(a: &mut App<SimBoard>) -> String {
    ["param", "cal", "limits", "solve 0.5 800 400 0", "status"].iter().map(|l| feed_text(a, format!("{l}\n").as_bytes())).collect()
}

/// [`transcript`] with the config fault left out (a board on the defaults after a refused
/// store answers as one on the defaults, but for `fault=config-rejected`).
fn transcript_but_fault(a: &mut App<SimBoard>) -> String {
    transcript(a).replace("fault=config-rejected", "fault=none")
}

#[test]
fn record_round_trip_and_distinct_tags() {
    let a = typed(SCRIPTS[1]);
    let rec = record_of(a.finger(), a.fw_params(), 7);
    let mut buf = [0u8; RECORD_MAX];
    let n = rec.encode(&mut buf);
    assert_eq!(Record::decode(&buf[..n]), Ok(rec.clone()));
    let mut tags: Vec<u16> = rec.values.iter().map(|v| v.0).collect();
    tags.sort();
    tags.dedup();
    assert_eq!(tags.len(), rec.values.len(), "two stored values share a tag");
    // every byte of the record is covered: any one flipped bit is refused
    for i in 0..n {
        let mut b = buf;
        b[i] ^= 0x10;
        assert!(Record::decode(&b[..n]).is_err(), "bit flip at byte {i} read as a record");
    }
    assert_eq!(Record::decode(&buf[..n - 1]), Err(FormatError::Length));
}

#[test]
fn saved_settings_survive_a_reset_and_factory_erases() {
    let flash = Flash::new(PAGES);
    let mut a = boot(&flash);
    assert_eq!(a.config_boot(), Boot::Empty);
    assert!(cmd(&mut a, "config").starts_with("ok store=empty saves=0 boot=empty fault=none"));
    run(&mut a, SCRIPTS[1]);
    assert_eq!(cmd(&mut a, "arm"), "ok armed=1");
    assert!(cmd(&mut a, "save").starts_with("err armed: "));
    assert!(cmd(&mut a, "factory").starts_with("err armed: "));
    assert_eq!(cmd(&mut a, "disarm"), "ok armed=0");
    let r = cmd(&mut a, "save");
    assert!(r.starts_with("ok saved=1 bytes="), "{r}");
    let want = transcript(&mut typed(SCRIPTS[1]));
    let mut b = boot(&flash);
    assert_eq!(b.config_boot(), Boot::Loaded);
    assert_eq!(transcript(&mut b), want);
    let c = cmd(&mut b, "config");
    assert!(c.starts_with("ok store=saved saves=1 boot=loaded fault=none format=1"), "{c}");
    assert_eq!(val(&c, "differ"), "10", "{c}"); // slew, servo_range, the 8 factors
                                                // each stored value under its own name
    let full = feed_text(&mut b, b"config\n");
    let mut names: Vec<&str> = full.lines().filter_map(|l| l.strip_prefix("stored ")?.split('=').next()).collect();
    names.sort_unstable();
    let mut want_names = vec!["h1", "h2", "h3", "h4", "ea0", "ea1", "ei0", "ei1", "slew", "servo_range"];
    want_names.sort_unstable();
    assert_eq!(names, want_names, "{full}");
    assert_eq!(cmd(&mut b, "factory"), "ok factory=1 store=empty");
    assert_eq!(transcript(&mut b), transcript(&mut typed(&[])));
    let mut c = boot(&flash);
    assert_eq!(c.config_boot(), Boot::Empty);
    assert_eq!(settings(&c), settings(&typed(&[])));
    assert_eq!(cmd(&mut c, "save"), format!("ok saved=1 bytes={}", val(&r, "bytes")));
}

/// Save the settings of `script` on a board booted on `flash`, the power cut after `cut`
/// bytes (None: no cut). The save's reply.
fn save_with_cut(flash: &Flash, script: &[&str], cut: Option<(u64, u8)>) -> String {
    let mut a = boot(flash);
    assert!(a.config_boot() == Boot::Loaded || a.config_boot() == Boot::Empty, "{:?}", a.config_boot());
    // from the compiled defaults (the preset brings their calibration) to the script's
    let _ = cmd(&mut a, "preset default");
    for (k, v) in [("slew", 2000.0), ("spool_r", 10.0), ("servo_range", 180.0), ("servo_dir", 1.0)] {
        let _ = cmd(&mut a, &format!("param {k} {v}"));
    }
    run(&mut a, script);
    if let Some((n, noise)) = cut {
        flash.cut_after(n, noise);
    }
    let r = cmd(&mut a, "save");
    flash.power_on();
    r
}

#[test]
fn a_cut_at_every_byte_of_a_save_leaves_the_old_or_the_new_settings() {
    let flash = Flash::new(PAGES);
    let want: Vec<(Vec<(u16, u32)>, String)> = SCRIPTS
        .iter()
        .map(|s| {
            let mut a = typed(s);
            (settings(&a), transcript(&mut a))
        })
        .collect();
    let mut old = 0; // the settings stored now (0: none, the defaults)
    let mut offsets = 0;
    let mut outcomes = [0usize; 2];
    // enough saves to fill every page and wrap: closes, migrations and erases are cut too
    for step in 0..12 {
        let new = 1 + step % (SCRIPTS.len() - 1);
        let probe = flash.fork();
        let before = probe.bytes_moved();
        assert!(save_with_cut(&probe, SCRIPTS[new], None).starts_with("ok saved="));
        let total = probe.bytes_moved() - before;
        let mut seen = [false; 2];
        // k = total: the save's last byte done, then the cut
        for k in 0..=total {
            let f = flash.fork();
            let r = save_with_cut(&f, SCRIPTS[new], Some((k, (k as u8).wrapping_mul(37))));
            assert_eq!(r.starts_with("err store: "), k < total, "cut at {k} of {total}: {r}");
            let mut b = boot(&f);
            // nothing stored before: the defaults, and a first save that left only a torn
            // item is unreadable bytes, shown as such
            let first = old == 0 && matches!(b.config_boot(), Boot::Empty | Boot::Rejected(Reject::Store(StoreError::Corrupted)));
            assert!(b.config_boot() == Boot::Loaded || first, "step {step} cut at {k}: {:?}", b.config_boot());
            let got = settings(&b);
            let which = if got == want[old].0 {
                0
            } else if got == want[new].0 {
                1
            } else {
                panic!("step {step} cut at {k}/{total}: a mix")
            };
            if !seen[which] {
                // the board answers as one given those settings at the console
                assert_eq!(transcript_but_fault(&mut b), want[[old, new][which]].1, "step {step} cut at {k}");
                seen[which] = true;
            }
            // the new settings once the save's last byte is written, never before (a torn
            // byte can equal the one meant, old AND new AND noise = new, e.g. a 0x00: then
            // the flash holds the whole save, as the uncut probe's)
            let whole = k == total || f.bytes() == probe.bytes();
            assert_eq!(which == 1, whole, "step {step} cut at {k}/{total}");
            outcomes[which] += 1;
            offsets += 1;
        }
        assert!(save_with_cut(&flash, SCRIPTS[new], None).starts_with("ok saved="));
        old = new;
    }
    println!("{offsets} cut offsets: old {} new {}", outcomes[0], outcomes[1]);
    assert!(outcomes[0] > 0 && outcomes[1] > 0);
}

/// The records of the scripts' settings, numbered.
fn records() -> Vec<Record> {
    SCRIPTS
        .iter()
        .enumerate()
        .map(|(i, s)| {
            let a = typed(s);
            record_of(a.finger(), a.fw_params(), 100 + i as u32)
        })
        .collect()
}

fn encode(r: &Record) -> Vec<u8> {
    let mut buf = [0u8; RECORD_MAX];
    let n = r.encode(&mut buf);
    buf[..n].to_vec()
}

/// The record a fresh boot's store reads on `flash` (decoded), or why not.
fn read_back(flash: &Flash) -> Result<Option<Record>, String> {
    let mut buf = [0u8; RECORD_MAX];
    let mut s = FlashStore::new(flash.clone(), 0..(PAGES * PAGE) as u32);
    match s.read(&mut buf) {
        Ok(None) => Ok(None),
        Ok(Some(n)) => Record::decode(&buf[..n]).map(Some).map_err(|e| format!("{e:?}")),
        Err(e) => Err(format!("{e:?}")),
    }
}

#[test]
fn random_sequences_of_saves_with_random_cuts_leave_old_or_new() {
    let n: usize = std::env::var("SETTINGS_SEQUENCES").ok().and_then(|s| s.parse().ok()).unwrap_or(10_000);
    let recs = records();
    let bytes: Vec<Vec<u8>> = recs.iter().map(encode).collect();
    let mut rng = Rng(0x5E77_1265);
    let mut flash = Flash::new(PAGES);
    let mut committed: Option<usize> = None;
    let (mut cuts, mut boots_checked) = (0, 0);
    for seq in 0..n {
        if seq % 64 == 0 {
            flash = Flash::new(PAGES);
            committed = None;
        }
        // 1..4 saves; the power cut somewhere in them (or in the boot's repair after), or not
        let saves = 1 + rng.below(4) as usize;
        let cut_at = if rng.below(8) == 0 { None } else { Some(rng.below(saves as u64 * 700)) };
        if let Some(c) = cut_at {
            flash.cut_after(c, rng.next() as u8);
        }
        let mut store = FlashStore::new(flash.clone(), 0..(PAGES * PAGE) as u32);
        let mut in_flight = None;
        for _ in 0..saves {
            let k = rng.below(recs.len() as u64) as usize;
            match store.write(&bytes[k]) {
                Ok(()) => committed = Some(k),
                Err(_) => {
                    in_flight = Some(k);
                    break;
                }
            }
        }
        if flash.is_off() {
            cuts += 1;
        }
        flash.power_on();
        // a boot cut during its own repair, sometimes: the boot after it must still agree
        if in_flight.is_some() && rng.below(4) == 0 {
            flash.cut_after(rng.below(2 * PAGE as u64), rng.next() as u8);
            let _ = read_back(&flash);
            flash.power_on();
        }
        // nothing committed yet: a torn first record is unreadable bytes (the defaults)
        let got = match read_back(&flash) {
            Err(e) if committed.is_none() && e == "Corrupted" => None,
            r => r.unwrap_or_else(|e| panic!("sequence {seq}: unreadable after a cut: {e}")),
        };
        let which = got.as_ref().map(|r| recs.iter().position(|x| x == r).unwrap_or_else(|| panic!("sequence {seq}: a record never saved: {r:?}")));
        assert!(
            which == committed || (in_flight.is_some() && which == in_flight),
            "sequence {seq}: read {which:?}, committed {committed:?}, in flight {in_flight:?}"
        );
        // stable: the next boot reads the same
        assert_eq!(read_back(&flash).ok().flatten(), got, "sequence {seq}");
        committed = which;
        if seq % 500 == 0 {
            let mut b = boot(&flash);
            let want = committed.map_or(0, |k| k);
            assert_eq!(settings(&b), settings(&typed(SCRIPTS[want])), "sequence {seq}");
            assert_eq!(transcript_but_fault(&mut b), transcript(&mut typed(SCRIPTS[want])), "sequence {seq}");
            boots_checked += 1;
        }
    }
    println!("{n} sequences, {cuts} cut, {boots_checked} boards compared");
    assert!(cuts > n / 2);
}

/// A board booted on a store holding `bytes` as its record.
fn boot_on_record(bytes: &[u8]) -> App<SimBoard> {
    let flash = Flash::new(PAGES);
    FlashStore::new(flash.clone(), 0..(PAGES * PAGE) as u32).write(bytes).unwrap();
    boot(&flash)
}

/// Refused whole: the compiled defaults in force and the fault shown.
fn assert_rejected(mut a: App<SimBoard>, why: &str) {
    assert!(matches!(a.config_boot(), Boot::Rejected(_)), "{why}: {:?}", a.config_boot());
    assert_eq!(settings(&a), settings(&typed(&[])), "{why}");
    let s = cmd(&mut a, "status");
    assert_eq!(val(&s, "fault"), "config-rejected", "{why}");
    let c = cmd(&mut a, "config");
    assert_eq!(val(&c, "boot"), "rejected", "{why}: {c}");
    assert_eq!(transcript_but_fault(&mut a), transcript(&mut typed(&[])), "{why}");
    // a fresh save clears it
    assert!(cmd(&mut a, "save").starts_with("ok saved=1"));
    assert_eq!(val(&cmd(&mut a, "status"), "fault"), "none");
}

/// The record of `script`'s settings with `edit` applied to its values, checksum valid.
fn forged(script: &[&str], edit: impl FnOnce(&mut Record)) -> Vec<u8> {
    let a = typed(script);
    let mut r = record_of(a.finger(), a.fw_params(), 9);
    edit(&mut r);
    encode(&r)
}

fn set(r: &mut Record, group: u8, name: &str, v: f32) {
    let t = tag(group, name);
    r.values.iter_mut().find(|x| x.0 == t).unwrap_or_else(|| panic!("{name}")).1 = v;
}

#[test]
fn records_with_a_valid_checksum_and_bad_values_are_refused_whole() {
    let cases: Vec<(&str, Vec<u8>, Reject)> = vec![
        ("slew past its range", forged(SCRIPTS[1], |r| set(r, b'f', "slew", 1e9)), Reject::Param("slew")),
        ("servo_dir 0", forged(SCRIPTS[1], |r| set(r, b'f', "servo_dir", 0.0)), Reject::Param("servo_dir")),
        ("margin 1.5", forged(SCRIPTS[1], |r| set(r, b'p', "margin", 1.5)), Reject::Param("margin")),
        ("NaN", forged(SCRIPTS[1], |r| set(r, b'p', "l", f32::NAN)), Reject::Param("l")),
        ("n = 4", forged(&[], |r| set(r, b'p', "n", 4.0)), Reject::Param("n")),
        ("2a >= l", forged(&[], |r| set(r, b'p', "a", 20.0)), Reject::Param("a")),
        ("a calibration factor of 100", forged(&[], |r| set(r, b'c', "h1", 100.0)), Reject::Calibration),
        ("preset 7", forged(&[], |r| r.preset = 7), Reject::Preset(7)),
        (
            "an unknown value",
            forged(&[], |r| {
                r.values.push((0xBEEF, 1.0)).unwrap();
            }),
            Reject::Unknown(0xBEEF),
        ),
        (
            "a repeated value",
            forged(&[], |r| {
                let v = r.values[0];
                r.values.push(v).unwrap();
            }),
            Reject::Duplicate(tag(b'p', "n")),
        ),
        ("half a calibration", forged(&[], |r| r.values.retain(|v| v.0 != tag(b'c', "ei1"))), Reject::Calibration),
        // (the board's film's hold ceiling binds, not the supply: a higher margin raises it)
        ("a raised ceiling (margin 0.99)", forged(&[], |r| set(r, b'p', "margin", 0.99)), Reject::Ceiling),
        (
            "a board constant (hv_fs)",
            forged(&[], |r| {
                r.values.push((tag(b'f', "hv_fs"), 20_000.0)).unwrap();
            }),
            Reject::BoardConstant("hv_fs"),
        ),
    ];
    for (why, bytes, reject) in cases {
        let a = boot_on_record(&bytes);
        assert_eq!(a.config_boot(), Boot::Rejected(reject), "{why}");
        assert_rejected(a, why);
    }
    // another format version, and not a record at all
    let mut v2 = encode(&records()[1]);
    v2[4] = 2;
    let a = boot_on_record(&v2);
    assert_eq!(a.config_boot(), Boot::Rejected(Reject::Format(FormatError::Version(2))));
    assert_rejected(a, "format 2");
    let a = boot_on_record(b"not a settings record at all");
    assert_eq!(a.config_boot(), Boot::Rejected(Reject::Format(FormatError::Magic)));
    assert_rejected(a, "not a record");
}

#[test]
fn a_record_lacking_values_keeps_their_compiled_defaults() {
    // an earlier build of the format that stored no `spool_r`: the default is kept
    let bytes = forged(&["param slew 700", "param spool_r 20"], |r| r.values.retain(|v| v.0 != tag(b'f', "spool_r")));
    let a = boot_on_record(&bytes);
    assert_eq!(a.config_boot(), Boot::Loaded);
    assert_eq!(settings(&a), settings(&typed(&["param slew 700"])));
    // none of the calibration factors: the calibration of the stored parameters, as typed
    let cal = ["h1", "h2", "h3", "h4", "ea0", "ea1", "ei0", "ei1"].map(|n| tag(b'c', n));
    let bytes = forged(&["param slew 700"], |r| r.values.retain(|v| !cal.contains(&v.0)));
    let a = boot_on_record(&bytes);
    assert_eq!(a.config_boot(), Boot::Loaded);
    assert_eq!(settings(&a), settings(&typed(&["param slew 700"])));
}

#[test]
fn save_refuses_settings_that_raise_the_ceiling() {
    let flash = Flash::new(PAGES);
    let mut a = boot(&flash);
    run(&mut a, SCRIPTS[2]);
    assert!(cmd(&mut a, "save").starts_with("ok saved=1"));
    let ceiling = finger_fw::app::config::board_ceiling();
    let mut raised = false;
    for line in ["param margin 0.99", "param v_supply 20000", "param g 2", "param z0 0.8", "param eps_r 2", "preset paper"] {
        let mut b = typed(&[]);
        run(&mut b, &[line]);
        if !(b.finger().ceiling_in_force(None) > ceiling) {
            continue;
        }
        raised = true;
        run(&mut a, &["preset default", line]);
        let r = cmd(&mut a, "save");
        assert!(r.starts_with("err limit: save: these settings raise the model's ceiling"), "{line}: {r}");
    }
    assert!(raised, "no console setting raises the ceiling past {ceiling} V: the refusal is untested here");
    // the store still holds the last good save
    let b = boot(&flash);
    assert_eq!(b.config_boot(), Boot::Loaded);
    assert_eq!(settings(&b), settings(&typed(SCRIPTS[2])));
}

#[test]
fn random_bytes_truncated_and_zeroed_sectors_are_refused() {
    let mut rng = Rng(0xC0_22_07);
    let defaults = settings(&typed(&[]));
    let mut rejected = 0;
    for i in 0..200 {
        let flash = Flash::new(PAGES);
        let mut noise = vec![0u8; PAGES * PAGE];
        for b in noise.iter_mut() {
            *b = rng.next() as u8;
        }
        // sometimes keep some pages erased, as a part-written store would
        if i % 2 == 1 {
            noise[PAGE..].fill(0xFF);
        }
        flash.set_bytes(&noise);
        let a = boot(&flash);
        assert_eq!(settings(&a), defaults, "random bytes {i} loaded as settings");
        assert!(matches!(a.config_boot(), Boot::Rejected(_)), "random bytes {i}: {:?}", a.config_boot());
        rejected += 1;
    }
    // a store of several saves, then a page truncated (its second half zeroed) or zeroed whole
    let recs = records();
    let saved = Flash::new(PAGES);
    let mut s = FlashStore::new(saved.clone(), 0..(PAGES * PAGE) as u32);
    for k in 0..5 {
        s.write(&encode(&recs[1 + k % 5])).unwrap();
    }
    for page in 0..PAGES {
        for (what, from) in [("zeroed", 0), ("truncated", PAGE / 2)] {
            let f = saved.fork();
            let mut b = f.bytes();
            b[page * PAGE + from..(page + 1) * PAGE].fill(0);
            f.set_bytes(&b);
            let a = boot(&f);
            match a.config_boot() {
                Boot::Rejected(_) => assert_eq!(settings(&a), defaults),
                // the map skips a torn record as after a power cut: a complete one saved before
                Boot::Loaded => assert!(recs.iter().any(|r| record_of(a.finger(), a.fw_params(), r.counter) == *r), "page {page} {what}: a record never saved"),
                b => panic!("page {page} {what}: {b:?}"),
            }
        }
    }
    println!("{rejected} random stores refused");
}

#[test]
fn factory_defaults_are_the_compiled_ones() {
    let a = typed(&[]);
    assert_eq!(a.finger().params(), default_finger().params());
    assert_eq!(a.finger().calibration(), default_finger().calibration());
    assert_eq!(*a.fw_params(), FwParams::default());
    assert!(settings_of(&record_of(a.finger(), a.fw_params(), 1)).is_ok());
}

/// The pages' bytes with one edit: in page `p`, the 8 bytes at `at` (from the page's start,
/// or from its end when `from_end`) set to `fill`, as a torn page mark or a cut erase leaves them.
fn edited(good: &[u8], p: usize, at: usize, from_end: bool, fill: u8) -> Vec<u8> {
    let mut b = good.to_vec();
    let start = if from_end { (p + 1) * PAGE - at - 8 } else { p * PAGE + at };
    b[start..start + 8].fill(fill);
    b
}

/// `config` while armed never writes the flash: an erase stalls every fetch from flash on the
/// board, the analog watchdog's handler included. Stores the map must repair (page marks
/// torn as a failed flash operation leaves them, in each page): armed, `config` answers
/// `err armed` without a byte moved; disarmed, it repairs and answers `ok`. Stores it reads
/// without a repair: `config` answers the same armed or not.
#[test]
fn config_while_armed_never_repairs_the_store() {
    // the stores after 1, 2, .. saves (the map closing, opening and migrating pages), each
    // with the edits near each page's marks; which of them a read repairs (on a copy)
    let flash = Flash::new(PAGES);
    let mut cases = Vec::new();
    for s in SCRIPTS.iter().skip(1).chain(SCRIPTS.iter().skip(1)) {
        assert!(save_with_cut(&flash, s, None).starts_with("ok saved="));
        let good = flash.bytes();
        for p in 0..PAGES {
            for at in (0..64).step_by(8) {
                for (from_end, fill) in [(false, 0), (false, 0xFF), (true, 0), (true, 0xFF)] {
                    let b = edited(&good, p, at, from_end, fill);
                    let probe = flash.fork();
                    probe.set_bytes(&b);
                    let st = store_on(&probe);
                    let _ = st.read(&mut [0u8; RECORD_MAX]);
                    let repairs = st.flash().erases + st.flash().writes > 0;
                    cases.push((flash.fork(), p, at, from_end, fill, b, repairs));
                }
            }
        }
    }
    let refused = cases.iter().filter(|c| c.6).count();
    assert!(refused > 0, "no edit needed a repair");
    // every store that needs a repair, and as many that do not
    let mut plain = 0;
    for (f, p, at, from_end, fill, b, repairs) in cases {
        if !repairs {
            if plain == refused {
                continue;
            }
            plain += 1;
        }
        let what = format!("page {p}, 8 bytes at {at}{} = {fill:#x}", if from_end { " from its end" } else { "" });
        let mut a = boot(&f);
        run(&mut a, &["arm"]);
        f.set_bytes(&b);
        let moved = f.bytes_moved();
        let armed = cmd(&mut a, "config");
        assert_eq!(f.bytes_moved(), moved, "{what}: `config` while armed moved bytes ({armed})");
        run(&mut a, &["stop"]);
        let disarmed = cmd(&mut a, "config");
        assert!(disarmed.starts_with("ok store="), "{what}, disarmed: {disarmed}");
        assert_eq!(f.bytes_moved() > moved, repairs, "{what}: disarmed, the repair");
        if repairs {
            assert!(armed.starts_with("err armed: config: the store needs a repair"), "{what}: {armed}");
        } else {
            assert_eq!(armed, disarmed, "{what}: read without a repair");
        }
    }
    println!("{refused} edits needed a repair: refused while armed");
}
