//! The config target: arbitrary stored bytes into the settings loader (`settings::Record::decode`,
//! then `app::config::settings_of`, what the boot applies).
//!
//! Input: `S` then 6-byte edits (value index, op, f32) to the compiled defaults' record (most
//! inputs reach the checks behind the format), or any other bytes as a stored record as they are.
//!
//! Invariants: a typed refusal (`FormatError`, `Reject`) or settings; a decoded record encodes
//! back to the same record; settings never raise the ceiling in force nor the model's own
//! (min(margin x V_pi, v_supply)) above the compiled defaults', and every firmware value is in
//! its range.
//!
//! What it is not: the flash store's power-cut behaviour (the settings' own tests).

use finger_fw::app::config::{default_finger, record_of, settings_of};
use finger_fw::app::{FwParams, FW_PARAMS};
use finger_fw::board::HV_MAX_V;
use finger_fw::settings::{Record, RECORD_MAX};

fn record_from(data: &[u8]) -> Option<Record> {
    if let Some((b'S', edits)) = data.split_first() {
        let mut rec = record_of(&default_finger(), &FwParams::default(), 1);
        for e in edits.chunks_exact(6) {
            let v = f32::from_le_bytes([e[2], e[3], e[4], e[5]]);
            let n = rec.values.len();
            match e[1] % 4 {
                0 if n > 0 => rec.values[e[0] as usize % n].1 = v,
                1 if n > 0 => rec.values[e[0] as usize % n].1 *= v,
                2 if n > 0 => {
                    rec.values.remove(e[0] as usize % n);
                }
                _ => rec.preset = e[0] % 3,
            }
        }
        Some(rec)
    } else {
        Record::decode(data).ok()
    }
}

/// Runs one input; panics when an invariant breaks.
pub fn check(data: &[u8]) {
    let Some(rec) = record_from(data) else { return };
    let mut buf = [0u8; RECORD_MAX];
    let len = rec.encode(&mut buf);
    let back = Record::decode(&buf[..len]).expect("a record written does not read back");
    let bits = |r: &Record| (r.counter, r.preset, r.values.iter().map(|&(t, v)| (t, v.to_bits())).collect::<Vec<_>>());
    assert_eq!(bits(&back), bits(&rec), "a record does not read back as written");
    let Ok((f, fw)) = settings_of(&rec) else { return };
    let d = default_finger();
    for cap in [Some(HV_MAX_V), None] {
        assert!(
            f.ceiling_in_force(cap) <= d.ceiling_in_force(cap),
            "stored settings raise the ceiling ({cap:?}): {} V past {} V",
            f.ceiling_in_force(cap),
            d.ceiling_in_force(cap)
        );
    }
    for i in FW_PARAMS.iter().filter(|i| i.min <= i.max) {
        let v = fw.get(i.name).unwrap_or(f32::NAN);
        assert!(v >= i.min && v <= i.max, "{} = {v} outside {}", i.name, i.range);
    }
}
