//! The stored settings' checks (docs/firmware.md "Settings"): what a record holds, read as the
//! console reads each value, and what the boot found ([`Boot`], [`Reject`]).
//!
//! What is stored: every console-settable value (the model's parameters but the read-only ones,
//! the calibration `cal`, the firmware parameters but the board constants) and the preset's
//! choice (the film's card and the DE modulus rule, which no parameter sets). A record is read
//! as a console `param` reads a value: each model parameter through `Params::set`, each firmware
//! parameter through its range, the calibration through `Finger::with_calibration`, and the
//! ceiling it gives never above the compiled defaults'. A record failing any check is refused
//! whole: the board keeps its compiled defaults and says so (boot banner, `config`, `status`
//! `fault=config-rejected`) until `factory` or a fresh `save`.
//!
//! What it is not: the record's bytes or the flash (`crate::settings`), the console's commands
//! on the store (`super::config`).

use core::fmt::Write;

use finger_model::params::PARAMS;
use finger_model::{Calibration, Finger, Params};
use finger_protocol::{const_concat, field};

use super::params::{board_params, calibration_for, default_finger, preset, FwParams, CAL_NAMES, CHANNELS, FW_PARAMS};
use crate::board::HV_MAX_V;
use crate::out::Emit;
use crate::settings::{tag, ConfigStore, FormatError, Record, StoreError, MAX_VALUES};

/// What the boot found in the store.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Boot {
    /// No store on this board (host `App::new`, a build without one).
    NoStore,
    /// Nothing stored: compiled defaults.
    Empty,
    /// The stored record is in force.
    Loaded,
    /// The stored record was refused: compiled defaults.
    Rejected(Reject),
}

/// The boot banner's word: `config=<none|empty|loaded>`, or `config=rejected reason=<why>
/// defaults`.
impl Emit for Boot {
    fn emit(&self, f: &mut dyn Write) {
        let _ = match self {
            Boot::NoStore => w!(f; const_concat!(field::CONFIG.first(), "none")),
            Boot::Empty => w!(f; const_concat!(field::CONFIG.first(), "empty")),
            Boot::Loaded => w!(f; const_concat!(field::CONFIG.first(), "loaded")),
            Boot::Rejected(e) => w!(f; const_concat!(field::CONFIG.first(), "rejected", field::REASON.after()), *e, " defaults"),
        };
    }
}

/// Why a record (or the store holding it) was refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Reject {
    /// The flash or the map could not be read.
    Store(StoreError),
    /// The bytes are not a record of this format.
    Format(FormatError),
    /// A value this build does not know (its tag), or one stored twice.
    Unknown(u16),
    Duplicate(u16),
    /// The preset byte is not a preset.
    Preset(u8),
    /// A parameter out of its range or inconsistent with the others.
    Param(&'static str),
    /// Calibration factors the model refuses, or only some of them stored.
    Calibration,
    /// Its ceiling is above the compiled board constants', before or after the HV modules'
    /// cap.
    Ceiling,
    /// A board constant (never stored: a read-only parameter).
    BoardConstant(&'static str),
    /// The read-back's calibration would loosen a ceiling or is out of its range (`hv_cal`).
    SenseCal,
}

impl Emit for Reject {
    fn emit(&self, f: &mut dyn Write) {
        let _ = match *self {
            Reject::Store(e) => w!(f; "store-", e.name()),
            Reject::Format(FormatError::Length) => w!(f; "length"),
            Reject::Format(FormatError::Magic) => w!(f; "not-a-record"),
            Reject::Format(FormatError::Version(v)) => w!(f; "format-v", v),
            Reject::Format(FormatError::Checksum) => w!(f; "checksum"),
            Reject::Unknown(t) => w!(f; "unknown-value-", t),
            Reject::Duplicate(t) => w!(f; "duplicate-value-", t),
            Reject::Preset(p) => w!(f; "preset-", p),
            Reject::Param(n) => w!(f; "param-", n),
            Reject::Calibration => w!(f; "cal"),
            Reject::Ceiling => w!(f; "ceiling"),
            Reject::BoardConstant(n) => w!(f; "board-constant-", n),
            Reject::SenseCal => w!(f; "sense-cal"),
        };
    }
}

/// The command side's view of its store.
pub(crate) struct ConfigState {
    pub(crate) store: Option<&'static mut dyn ConfigStore>,
    pub(crate) boot: Boot,
    /// The counter of the newest record saved or loaded (0: none since boot or `factory`).
    pub(crate) saves: u32,
    /// The boot's refusal stands (cleared by `save` and `factory`).
    pub(crate) rejected: bool,
}

impl ConfigState {
    pub(crate) const fn new() -> Self {
        ConfigState { store: None, boot: Boot::NoStore, saves: 0, rejected: false }
    }
}

/// The stored model parameters: every one the console can set.
pub(crate) fn model_names() -> impl Iterator<Item = &'static str> {
    PARAMS.iter().filter(|i| !i.read_only).map(|i| i.name)
}
/// The stored firmware parameters: every one the console can set (not the board constants).
pub(crate) fn fw_names() -> impl Iterator<Item = &'static str> {
    FW_PARAMS.iter().filter(|i| i.min <= i.max).map(|i| i.name)
}

/// The settings a record holds, checked as the console checks them; refused whole on any
/// failure. Values the record lacks keep their compiled defaults (a record of an earlier
/// build of this format).
pub fn settings_of(rec: &Record) -> Result<(Finger<f32>, FwParams), Reject> {
    let mut p = match rec.preset {
        0 => preset(board_params()),
        1 => preset(Params::paper()),
        k => return Err(Reject::Preset(k)),
    };
    let mut model: heapless::Vec<(&'static str, f32), MAX_VALUES> = heapless::Vec::new();
    let mut cal = [None; 8];
    let mut fw = FwParams::default();
    let mut seen: heapless::Vec<u16, MAX_VALUES> = heapless::Vec::new();
    for &(t, v) in &rec.values {
        if seen.contains(&t) {
            return Err(Reject::Duplicate(t));
        }
        let _ = seen.push(t);
        if let Some(name) = model_names().find(|n| tag(b'p', n) == t) {
            let _ = model.push((name, v));
        } else if let Some(k) = CAL_NAMES.iter().position(|n| tag(b'c', n) == t) {
            cal[k] = Some(v);
        } else if let Some(name) = fw_names().find(|n| tag(b'f', n) == t) {
            fw.set(name, v).map_err(|_| Reject::Param(name))?;
        } else if cfg!(not(m3)) && super::hv_cal::slot_of(t).is_some() {
            // the read-back's calibration: checked whole below
        } else if let Some(i) = PARAMS.iter().map(|i| i.name).chain(FW_PARAMS.iter().map(|i| i.name)).find(|n| tag(b'p', n) == t || tag(b'f', n) == t) {
            return Err(Reject::BoardConstant(i));
        } else {
            return Err(Reject::Unknown(t));
        }
    }
    // each through `Params::set`, in passes: a value the set refuses now may pass once the
    // others it is tied to (2a < l, t_min < b, ...) are in
    while !model.is_empty() {
        let before = model.len();
        model.retain(|&(name, v)| p.set(name, v as f64).is_err());
        if model.len() == before {
            return Err(Reject::Param(model[0].0));
        }
    }
    if p.n != CHANNELS {
        return Err(Reject::Param("n"));
    }
    if !cfg!(feature = "de") && p.layers != 0 {
        return Err(Reject::Param("layers"));
    }
    #[cfg(not(m3))]
    super::hv_cal::sense_cal_of(rec).map_err(|_| Reject::SenseCal)?;
    let cal = match cal {
        [None, None, None, None, None, None, None, None] => calibration_for(&p),
        [Some(h1), Some(h2), Some(h3), Some(h4), Some(a0), Some(a1), Some(b0), Some(b1)] => {
            Calibration { hinge: [h1, h2, h3, h4], stack_axial: [a0, a1], stack_bending: [b0, b1] }
        }
        _ => return Err(Reject::Calibration),
    };
    let f = Finger::with_calibration(p, cal).map_err(|_| Reject::Calibration)?;
    // the ceiling in force and the model's own, min(margin x V_pi, v_supply), before the HV
    // modules' cap: a stored value may lower either, never raise one
    let d = default_finger();
    for cap in [Some(HV_MAX_V), None] {
        if !(f.ceiling_in_force(cap) <= d.ceiling_in_force(cap)) {
            return Err(Reject::Ceiling);
        }
    }
    Ok((f, fw))
}

/// The model's ceiling of the compiled defaults before the HV modules' cap, V: what the board
/// constants allow a stored setting (`save` and the boot refuse more).
pub fn board_ceiling() -> f32 {
    default_finger().ceiling_in_force(None)
}

/// The settings `finger` and `fw` and the read-back's calibration `sense` (its values only
/// when not nominal) as a record numbered `counter`.
#[cfg(not(m3))]
pub fn record_with(finger: &Finger<f32>, fw: &FwParams, sense: &super::hv_cal::SenseCal, counter: u32) -> Record {
    let mut rec = record_of(finger, fw, counter);
    super::hv_cal::push_values(sense, &mut rec.values);
    rec
}

/// The settings `finger` and `fw` as a record numbered `counter`.
pub fn record_of(finger: &Finger<f32>, fw: &FwParams, counter: u32) -> Record {
    let p = finger.params();
    let mut values = heapless::Vec::new();
    for name in model_names() {
        let _ = values.push((tag(b'p', name), p.get(name).unwrap_or(f64::NAN) as f32));
    }
    let c = finger.calibration();
    let g = [c.hinge[0], c.hinge[1], c.hinge[2], c.hinge[3], c.stack_axial[0], c.stack_axial[1], c.stack_bending[0], c.stack_bending[1]];
    for (name, v) in CAL_NAMES.iter().zip(g) {
        let _ = values.push((tag(b'c', name), v));
    }
    for name in fw_names() {
        let _ = values.push((tag(b'f', name), fw.get(name).unwrap_or(f32::NAN)));
    }
    // the paper's preset is the one on the paper's card (the DE modulus rule and the
    // film, which no parameter sets); any other started from the board's
    let preset = if p.card == Params::<f32>::paper().card { 1 } else { 0 };
    Record { counter, preset, values }
}

/// A stored value's console name, from its tag (`?` for a tag this build does not know).
pub(crate) fn name_of(t: u16) -> &'static str {
    if let Some(n) = model_names().find(|n| tag(b'p', n) == t) {
        return n;
    }
    if let Some(n) = CAL_NAMES.iter().find(|n| tag(b'c', n) == t) {
        return n;
    }
    #[cfg(not(m3))]
    if let Some((k, j)) = super::hv_cal::slot_of(t) {
        return super::hv_cal::NAMES[k][j];
    }
    fw_names().find(|n| tag(b'f', n) == t).unwrap_or("?")
}
