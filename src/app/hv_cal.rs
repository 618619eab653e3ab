//! The read-back's calibration on the command side: each channel's voltage monitor (gain,
//! offset) and each stack's capacitance at 0 V (C0), the console's `cal show|vmon|c0`, their
//! place in the stored record (values `h:vgain<k>`, `h:voff<k>`, `h:c0_<k>`; absent: nominal)
//! and their way to the control core (`Commands::take_sense_cal`).
//!
//! The rule: a calibration never loosens a ceiling. A monitor that would read lower than the
//! nominal chain is refused (`MonitorCal::checked`): the loop would drive the output past what
//! it reads. A C0 is taken only in its range; one that makes the sensed film thicker than the
//! model's raises nothing, as the guard keeps the thinner (`control::watch::ThicknessGuard`).
//! Not here: what the core does with them (`control::sense`, `control::watch`).

use core::fmt::Write;

use super::commands::Commands;
use super::errors::{number, CmdError};
use super::help::Reply;
use crate::board::{BOARD_STACK_C0_PF, HV_CHANNELS};
use crate::control::sense::MonitorCal;
use crate::num::Fixed;

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
        (c0_pf >= BOARD_STACK_C0_PF / C0_RANGE && c0_pf <= BOARD_STACK_C0_PF * C0_RANGE).then_some(c0_pf).ok_or(CalRefused::C0Range)
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

fn channel(w: &[u8]) -> Result<usize, CmdError> {
    match w {
        b"1" => Ok(0),
        b"2" => Ok(1),
        b"3" => Ok(2),
        _ => Err(err!("usage"; "cal: channel 1..3")),
    }
}

fn value(w: &[u8], name: &str) -> Result<f32, CmdError> {
    number(w, name)
}

impl Commands {
    /// `cal show | vmon <ch> <gain> <offset V> | c0 <ch> <pF>`: the read-back's calibration;
    /// a change only while disarmed, refused whole (nothing changes) by the rule above; in
    /// force at once, stored by `save`.
    pub(super) fn cmd_cal_hv(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        let mut c = self.sense_cal;
        match args {
            [w] if *w == b"show" => {}
            [w, ch, g, o] if *w == b"vmon" => {
                let k = channel(ch)?;
                let (g, o) = (value(g, "gain")?, value(o, "offset")?);
                self.require_disarmed("cal")?;
                c.monitor[k] = MonitorCal::checked(g, o).ok_or_else(|| {
                    err!("limit"; "cal vmon: gain ", Fixed(g, 4), " offset ", Fixed(o, 1), " V reads below the nominal chain or past its range (gain 1..1.2, offset 0..200 V): the loop would drive past what it reads; refused")
                })?;
            }
            [w, ch, pf] if *w == b"c0" => {
                let k = channel(ch)?;
                let pf = value(pf, "c0")?;
                self.require_disarmed("cal")?;
                c.c0_pf[k] = SenseCal::c0_checked(pf).map_err(|_| err!("usage"; "cal c0: ", Fixed(pf, 1), " pF outside ", Fixed(BOARD_STACK_C0_PF / C0_RANGE, 1), "..", Fixed(BOARD_STACK_C0_PF * C0_RANGE, 1), " pF; refused"))?;
            }
            _ => return Err(err!("usage"; "cal show | cal vmon <ch> <gain> <offset V> | cal c0 <ch> <pF>")),
        }
        if c != self.sense_cal {
            self.sense_cal = c;
            self.sense_cal_req = Some(c);
        }
        write_cal(r, &self.sense_cal);
        Ok(())
    }

    /// A calibration for the control core, once (the hand-over after a line, the boot).
    pub fn take_sense_cal(&mut self) -> Option<SenseCal> {
        self.sense_cal_req.take()
    }

    /// The read-back's calibration in force.
    pub fn sense_cal(&self) -> SenseCal {
        self.sense_cal
    }
}

/// `vgain=g1,g2,g3 voff=o1,o2,o3 c0_pf=c1,c2,c3`.
fn write_cal(r: &mut dyn Write, c: &SenseCal) {
    let _ = w!(r; "vgain=");
    for k in 0..HV_CHANNELS {
        let _ = w!(r; if k > 0 { "," } else { "" }, Fixed(c.monitor[k].gain, 4));
    }
    let _ = w!(r; " voff=");
    for k in 0..HV_CHANNELS {
        let _ = w!(r; if k > 0 { "," } else { "" }, Fixed(c.monitor[k].offset_v, 1));
    }
    let _ = w!(r; " c0_pf=");
    for k in 0..HV_CHANNELS {
        let _ = w!(r; if k > 0 { "," } else { "" }, Fixed(c.c0_pf[k], 2));
    }
}
