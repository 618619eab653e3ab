//! `plant ...`: the test console of the simulated HV plant (docs/firmware.md "The plant"),
//! in finger-sim and the emulator image, never in the board build. Each line is parsed and
//! checked here; the request goes to the control core, which owns the board and its plant
//! ([`crate::control::Control::plant_request`]); `plant status` reads the plant's truth from
//! the core's view.

use finger_protocol::{const_concat, field};

use super::commands::Commands;
use super::errors::{number, CmdError};
use super::help::{list, Reply};
use crate::console;
use crate::control::PlantRequest;
use crate::num::Fixed;
use crate::plant::Inject;

/// The channel of `plant <what> <ch>`, 1-based on the console.
fn channel(c: &[u8]) -> Result<usize, CmdError> {
    match c {
        b"1" => Ok(0),
        b"2" => Ok(1),
        b"3" => Ok(2),
        c => Err(err!(Usage; "plant: channel ", (console::printable(c)), " is not 1, 2 or 3")),
    }
}

const USAGE: &str =
    "plant film <G_eq kPa> [time scale] | breakdown <ch> [clears after ms] | stuck <ch> <V> | open <ch> | leak <ch> <MOhm> | gain <ch> <x> | monitor <ch> <code> | status";

impl Commands {
    #[inline(never)]
    pub(super) fn cmd_plant(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        if self.plant_view.is_none() {
            return Err(err!(Unknown; "plant: this board has no plant"));
        }
        let Some((&what, rest)) = args.split_first() else { return Err(err!(Usage; USAGE)) };
        let req = match (what, rest) {
            (b"status", []) => {
                let Some(pv) = self.plant_view else { return Err(err!(Unknown; "plant: this board has no plant")) };
                let stack_mm = self.stack_mm();
                let mut t = [0.0f32; 3];
                for ch in 0..3 {
                    t[ch] = pv.s[ch] * stack_mm;
                }
                let _ = w!(r; const_concat!("plant", field::FILM_KPA.after()), Fixed(pv.film_kpa, 2), field::VOLTS.after());
                list(r, &pv.volts, 1);
                let _ = w!(r; field::CURRENT_UA.after());
                list(r, &pv.current_ua, 3);
                let _ = w!(r; field::THICK.after());
                list(r, &t, 4);
                let _ = w!(r; field::TRIP_US.after(), self.trip_max_us.unwrap_or(0));
                return Ok(());
            }
            (b"film", [g]) | (b"film", [g, _]) => {
                let g = number(g, "kPa")?;
                let ts = match rest.get(1) {
                    Some(x) => number(x, "time scale")?,
                    None => 1.0,
                };
                if !(1.0..=100.0).contains(&g) || !(1.0..=1000.0).contains(&ts) {
                    return Err(err!(Usage; "plant film: G_eq 1..100 kPa, time scale 1..1000"));
                }
                PlantRequest::Film { g_eq_kpa: g, time_scale: ts }
            }
            (b"breakdown", [c]) => PlantRequest::Inject(channel(c)?, Inject::Breakdown { clears_after_ms: None }),
            (b"breakdown", [c, ms]) => {
                let ms = number(ms, "ms")?;
                if !(1.0..=60_000.0).contains(&ms) {
                    return Err(err!(Usage; "plant breakdown: clears after 1..60000 ms"));
                }
                PlantRequest::Inject(channel(c)?, Inject::Breakdown { clears_after_ms: Some(ms as u32) })
            }
            (b"stuck", [c, v]) => {
                let v = number(v, "V")?;
                if !(0.0..=12_000.0).contains(&v) {
                    return Err(err!(Usage; "plant stuck: 0..12000 V"));
                }
                PlantRequest::Inject(channel(c)?, Inject::Stuck(v))
            }
            (b"open", [c]) => PlantRequest::Inject(channel(c)?, Inject::Open),
            (b"leak", [c, mohm]) => {
                let m = number(mohm, "MOhm")?;
                if !(m > 0.0 && m <= 1e9) {
                    return Err(err!(Usage; "plant leak: > 0 MOhm"));
                }
                PlantRequest::Inject(channel(c)?, Inject::Leak(m * 1e6))
            }
            (b"gain", [c, x]) => {
                let x = number(x, "gain")?;
                if !(x > 0.0 && x <= 2.0) {
                    return Err(err!(Usage; "plant gain: 0..2"));
                }
                PlantRequest::Inject(channel(c)?, Inject::Gain(x))
            }
            (b"monitor", [c, code]) => {
                let code = number(code, "code")?;
                if !(0.0..=4095.0).contains(&code) {
                    return Err(err!(Usage; "plant monitor: code 0..4095"));
                }
                PlantRequest::Inject(channel(c)?, Inject::MonitorStuck(code))
            }
            _ => return Err(err!(Usage; USAGE)),
        };
        self.plant_req = Some(req);
        let _ = w!(r; "plant ", (console::printable(what)));
        for a in rest {
            let _ = w!(r; " ", (console::printable(a)));
        }
        Ok(())
    }

    /// The plant request of the last line, for the control core.
    pub fn take_plant(&mut self) -> Option<PlantRequest> {
        self.plant_req.take()
    }
}
