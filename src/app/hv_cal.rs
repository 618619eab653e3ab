//! The read-back's calibration on the command side: each channel's voltage monitor (gain,
//! offset) and each stack's capacitance at 0 V (C0), the console's `cal show|vmon|c0`, their
//! place in the stored record (values `h:vgain<k>`, `h:voff<k>`, `h:c0_<k>`; absent: nominal)
//! and their way to the control core (`Commands::take_sense_cal`); the commands themselves are
//! `super::hv_cal_cmd`.
//!
//! The rule: a calibration never loosens a ceiling. A monitor that would read lower than the
//! nominal chain is refused (`MonitorCal::checked`): the loop would drive the output past what
//! it reads. A C0 is taken only in its range; one that makes the sensed film thicker than the
//! model's raises nothing, as the guard keeps the thinner (`control::watch::ThicknessGuard`).
//! Not here: what the core does with them (`control::sense`, `control::watch`).

use crate::board::{BOARD_STACK_C0_PF, HV_CHANNELS};
use crate::control::sense::MonitorCal;

/// A stack's C0 is taken within this factor of the board's (`BOARD_STACK_C0_PF`) either way.
pub const C0_RANGE: f32 = 2.0;

/// The read-back's calibration in force.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct SenseCal {
    pub monitor: [MonitorCal; HV_CHANNELS],
    pub c0_pf: [f32; HV_CHANNELS],
}

/// Why a calibration is refused.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum CalRefused {
    /// The monitor would read below the nominal chain (gain < 1 or offset < 0), or past its range.
    MonitorLow,
    /// C0 outside 1/[`C0_RANGE`]..[`C0_RANGE`] x the board's, or not finite.
    C0Range,
}

impl SenseCal {
    pub const NOMINAL: SenseCal = SenseCal { monitor: [MonitorCal::NOMINAL; HV_CHANNELS], c0_pf: [BOARD_STACK_C0_PF; HV_CHANNELS] };

    /// A C0 in its range, pF.
    pub fn c0_checked(c0_pf: f32) -> Result<f32, CalRefused> {
        (BOARD_STACK_C0_PF / C0_RANGE..=BOARD_STACK_C0_PF * C0_RANGE).contains(&c0_pf).then_some(c0_pf).ok_or(CalRefused::C0Range)
    }

    /// Every channel's values through their checks.
    pub fn checked(&self) -> Result<SenseCal, CalRefused> {
        for k in 0..HV_CHANNELS {
            MonitorCal::checked(self.monitor[k].gain, self.monitor[k].offset_v).ok_or(CalRefused::MonitorLow)?;
            Self::c0_checked(self.c0_pf[k])?;
        }
        Ok(*self)
    }
}

/// The stored values' names, per channel k (1-based in the name).
#[cfg(feature = "settings")]
pub(crate) const NAMES: [[&str; 3]; HV_CHANNELS] = [["vgain1", "voff1", "c0_1"], ["vgain2", "voff2", "c0_2"], ["vgain3", "voff3", "c0_3"]];

/// Of a stored value's tag: its channel and which value (0 gain, 1 offset, 2 C0).
#[cfg(feature = "settings")]
pub(crate) fn slot_of(t: u16) -> Option<(usize, usize)> {
    for (k, names) in NAMES.iter().enumerate() {
        if let Some(j) = names.iter().position(|n| crate::settings::tag(b'h', n) == t) {
            return Some((k, j));
        }
    }
    None
}

/// A record's calibration: its `h:` values over the nominal ones, checked whole.
#[cfg(feature = "settings")]
pub fn sense_cal_of(rec: &crate::settings::Record) -> Result<SenseCal, CalRefused> {
    let mut c = SenseCal::NOMINAL;
    for &(t, v) in &rec.values {
        match slot_of(t) {
            Some((k, 0)) => c.monitor[k].gain = v,
            Some((k, 1)) => c.monitor[k].offset_v = v,
            Some((k, _)) => c.c0_pf[k] = v,
            None => {}
        }
    }
    c.checked()
}

/// The calibration's values for a record: none when nominal (a record of a board never
/// calibrated is as before).
#[cfg(feature = "settings")]
pub(crate) fn push_values(cal: &SenseCal, values: &mut heapless::Vec<(u16, f32), { crate::settings::MAX_VALUES }>) {
    if *cal == SenseCal::NOMINAL {
        return;
    }
    for (k, names) in NAMES.iter().enumerate() {
        let v = [cal.monitor[k].gain, cal.monitor[k].offset_v, cal.c0_pf[k]];
        for (n, x) in names.iter().zip(v) {
            let _ = values.push((crate::settings::tag(b'h', n), x));
        }
    }
}
