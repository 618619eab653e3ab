//! The console's `cal show|vmon|c0` (docs/console.md): the read-back's calibration
//! (`super::hv_cal`) read, or set while disarmed through its checks, and handed to the core.

use core::fmt::Write;

use finger_protocol::field;

use super::commands::Commands;
use super::errors::{number, CmdError};
use super::help::Reply;
use super::hv_cal::{SenseCal, C0_RANGE};
use crate::board::{BOARD_STACK_C0_PF, HV_CHANNELS};
use crate::control::sense::MonitorCal;
use crate::num::Fixed;

fn channel(w: &[u8]) -> Result<usize, CmdError> {
    match w {
        b"1" => Ok(0),
        b"2" => Ok(1),
        b"3" => Ok(2),
        _ => Err(err!(Usage; "cal: channel 1..3")),
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
                    err!(Limit; "cal vmon: gain ", Fixed(g, 4), " offset ", Fixed(o, 1), " V reads below the nominal chain or past its range (gain 1..1.2, offset 0..200 V): the loop would drive past what it reads; refused")
                })?;
            }
            [w, ch, pf] if *w == b"c0" => {
                let k = channel(ch)?;
                let pf = value(pf, "c0")?;
                self.require_disarmed("cal")?;
                c.c0_pf[k] = SenseCal::c0_checked(pf).map_err(|_| err!(Usage; "cal c0: ", Fixed(pf, 1), " pF outside ", Fixed(BOARD_STACK_C0_PF / C0_RANGE, 1), "..", Fixed(BOARD_STACK_C0_PF * C0_RANGE, 1), " pF; refused"))?;
            }
            _ => return Err(err!(Usage; "cal show | cal vmon <ch> <gain> <offset V> | cal c0 <ch> <pF>")),
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
    let _ = w!(r; field::VGAIN.first());
    for k in 0..HV_CHANNELS {
        let _ = w!(r; if k > 0 { "," } else { "" }, Fixed(c.monitor[k].gain, 4));
    }
    let _ = w!(r; field::VOFF.after());
    for k in 0..HV_CHANNELS {
        let _ = w!(r; if k > 0 { "," } else { "" }, Fixed(c.monitor[k].offset_v, 1));
    }
    let _ = w!(r; field::C0_PF.after());
    for k in 0..HV_CHANNELS {
        let _ = w!(r; if k > 0 { "," } else { "" }, Fixed(c.c0_pf[k], 2));
    }
}
