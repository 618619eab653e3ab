//! `help` and the replies' shared formatting: the command list, number lists, a tip pose, the
//! joints and `solve`'s reply.
//!
//! What it is not: numbers' text itself (`crate::num`, `crate::out`).

use core::fmt::Write;

use finger_protocol::field;
use heapless::String;

use super::errors::CmdError;
use super::params::CHANNELS;
use super::solves::Solved;
use crate::num::{Exp, Fixed, List};
use crate::out::Emit;

/// A reply line being built (without `ok ` and the line ending).
#[cfg(m3)]
pub(crate) type Reply = String<400>;
/// (the read-back's fields make `status` longer than the M3 image's)
#[cfg(not(m3))]
pub(crate) type Reply = String<480>;

/// Radians to degrees.
pub(crate) const DEG: f32 = 180.0 / core::f32::consts::PI;

/// One `help` line: `syntax - description`; the Cortex-M3 image keeps the syntax alone (its
/// flash budget).
macro_rules! help_line {
    ($syntax:literal, $what:literal) => {
        if cfg!(m3) {
            $syntax
        } else {
            concat!($syntax, " - ", $what)
        }
    };
}

// same shape entry after entry: one `help_line!` per command, each its own text
pub(crate) const HELP: &[&str] = &[
    help_line!("help", "this list"),
    help_line!("version", "firmware name and version"),
    help_line!("status", "outputs, setpoints, model state, fault"),
    help_line!("limits", "ceilings in force"),
    #[cfg(not(m3))]
    help_line!("material", "the board's film: card, moduli, permittivity, breakdown, hold ceiling"),
    help_line!("solve <P> <V1> <V2> <V3>", "model only, nothing moves"),
    #[cfg(feature = "shape")]
    help_line!("shape <P> <V1> <V2> <V3>", "model only: node and hinge-end poses of that solve"),
    help_line!("arm | disarm", "allow HV / ramp HV to 0, then drop the enable"),
    help_line!("stop", "emergency stop: HV off at once, cable released, disarmed"),
    help_line!("volt <1|2|3|all> <V>", "HV channel setpoint, slewed; needs arm"),
    help_line!("force <P>", "cable tension (servo); needs arm"),
    #[cfg(m3)]
    help_line!("pose <d1> <d2> <d3> [<P>]", "inverse (fixed point): tension and voltages for these joint angles (deg); moves only when armed"),
    #[cfg(feature = "pose")]
    help_line!("pose <d1> <d2> <d3> [<P>]", "inverse: tension and voltages for these joint angles (deg); moves only when armed"),
    #[cfg(feature = "contact")]
    help_line!("contact <P0> <P> [<V1> <V2> <V3>]", "model only: tip force on a stop at the free tip of P0"),
    help_line!("param [<name> [<value>]]", "list, read or set a parameter; only while disarmed"),
    help_line!("preset <default|paper>", "model parameters back to a preset; only while disarmed"),
    help_line!("cal [<h1> <h2> <h3> <h4> <ea0> <ea1> <ei0> <ei1> | none]", "FE calibration factors: read, set or clear (set and clear only while disarmed)"),
    #[cfg(not(m3))]
    help_line!(
        "cal show | vmon <ch> <gain> <offset V> | c0 <ch> <pF>",
        "HV read-back calibration: monitors, stacks' C0 (only tightens; set only while disarmed; save stores it)"
    ),
    help_line!("wait <s>", "run the control loop for s seconds, then reply"),
    #[cfg(all(target_os = "none", not(m3)))]
    help_line!("reset", "reboot the board (as at power-up: the stored settings, or the compiled defaults); only while disarmed"),
    #[cfg(feature = "settings")]
    help_line!("save", "keep the settings in force across resets; only while disarmed"),
    #[cfg(feature = "settings")]
    help_line!("config", "what is stored, its save counter, what the boot loaded"),
    #[cfg(feature = "settings")]
    help_line!("factory", "erase the stored settings, back to the compiled defaults; only while disarmed"),
];

/// `help`'s line for `timing`, listed where the runtime measures (the chip images).
pub(crate) const HELP_TIMING: &str = help_line!("timing", "the board's own real-time measurements: tick period, latency, stop, command durations");

/// `help`'s line for `plant`, listed where a simulated plant answers it (finger-sim, the
/// emulator image; docs/firmware.md "The plant").
#[cfg(not(feature = "hw"))]
pub(crate) const HELP_PLANT: &str = help_line!(
    "plant film <G_eq kPa> [time scale] | breakdown <ch> [clears after ms] | stuck <ch> <V> | open <ch> | leak <ch> <MOhm> | gain <ch> <x> | monitor <ch> <code> | status",
    "the simulated HV plant's test console: change its film, inject a fault, read its truth"
);

/// Whether `word` (lowercase) is a command of this build's `help` (or `timing`): the first
/// word of each alternative of a line's syntax. `timing`'s durations file the rest under
/// `unknown`. The Cortex-M3 image calls every word a command (360 bytes its flash lacks).
pub fn is_command(word: &[u8]) -> bool {
    if cfg!(m3) {
        return true;
    }
    if word == b"timing" || (cfg!(not(feature = "hw")) && word == b"plant") {
        return true;
    }
    // byte by byte (no string search in the M3 image's flash): a line's first word, or the
    // word after a `|` alone, up to the description's `-`
    for l in HELP {
        let mut first = true;
        for t in l.as_bytes().split(|&c| c == b' ') {
            if t == b"-" {
                break;
            }
            if first && t == word {
                return true;
            }
            first = t == b"|";
        }
    }
    false
}

pub(crate) fn list(r: &mut Reply, v: &[f32], prec: usize) {
    let _ = w!(r; List(v, prec));
}

/// A tip pose as `x,y,deg` (mm, mm, degrees).
pub(crate) struct Tip<'a>(pub(crate) &'a finger_model::Pose<f32>);

impl Emit for Tip<'_> {
    fn emit(&self, f: &mut dyn Write) {
        let t = self.0;
        let _ = w!(f; Fixed(t.x, 3), ",", Fixed(t.y, 3), ",", Fixed(t.theta * DEG, 2));
    }
}

/// `solve`'s reply: joints, tip, cable, thicknesses, tip stiffness, iterations.
pub(crate) fn solve_reply(r: &mut Reply, sol: &Solved, k: finger_model::mat3::Mat3<f32>) -> Result<(), CmdError> {
    let _ = w!(r; field::JOINTS.first());
    joints(r, sol);
    let tip = sol.tip();
    let _ = w!(r; field::TIP.after(), Tip(&tip), field::CABLE.after(), Fixed(sol.cable_excursion, 4), field::THICK.after());
    list(r, &sol.thickness[..CHANNELS], 4);
    let _ = w!(r; field::STIFFNESS.after(), Exp(k[0][0], 4), ",", Exp(k[1][1], 4), ",", Exp(k[2][2], 4), field::ITERS.after(), sol.iterations);
    Ok(())
}

pub(crate) fn joints(r: &mut Reply, s: &Solved) {
    let mut d = [0.0f32; CHANNELS];
    for ch in 0..CHANNELS {
        d[ch] = s.joint_angle[ch] * DEG;
    }
    list(r, &d, 3);
}
