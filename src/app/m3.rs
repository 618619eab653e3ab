//! The Cortex-M3 image's model calls (`cfg(m3)`, docs/firmware.md "Cortex-M3 image"): the
//! console's forward solves (`solve`, `status`, the servo plan) and fmax on the fixed-point
//! model (`finger_model::fixed`, docs/fixed-point.md) instead of the f32 model in soft float.
//! The set-up (compliances at the voltages) is the f32 model's; the solve has no float
//! operation. Not here: the tip stiffness (`solve` answers `stiffness=-,-,-`).

use finger_model::fixed::q::Nt;
use finger_model::fixed::FixedFinger;
use finger_model::Pose;

use super::*;

/// What the console prints of a forward solve (the f32 `Solution`'s fields it reads).
pub(super) struct Solved {
    pub joint_angle: [f32; CHANNELS],
    pub cable_excursion: f32,
    pub thickness: [f32; CHANNELS],
    pub iterations: u32,
    tip: Pose<f32>,
}

impl Solved {
    pub fn tip(&self) -> Pose<f32> {
        self.tip
    }
}

/// The converged equilibrium under tension `p` (N) alone at `volts`, in fixed point.
#[inline(never)]
pub(super) fn forward(f: &Finger<f32>, p: f32, volts: &[f32; CHANNELS]) -> Result<Solved, ModelError> {
    let s = FixedFinger::new(f, volts)?.solve(Nt::from_f32(p))?;
    let mut out = Solved { joint_angle: [0.0; CHANNELS], cable_excursion: s.cable_excursion.to_f32(), thickness: [0.0; CHANNELS], iterations: s.iterations, tip: Pose::origin() };
    for k in 0..CHANNELS {
        out.joint_angle[k] = s.joint_angle[k].to_f32();
        if f.params().layers > 0 {
            out.thickness[k] = f.stack_thickness(volts[k])?;
        }
    }
    let t = s.tip();
    out.tip = Pose { x: t.x.to_f32(), y: t.y.to_f32(), theta: t.theta.to_f32() };
    Ok(out)
}

/// fmax at `volts`: the largest tension the fixed-point solve holds (`FixedFinger::branch_end`).
#[inline(never)]
pub(super) fn fmax_of(f: &Finger<f32>, volts: &[f32; CHANNELS]) -> Result<BranchLimit<f32>, ModelError> {
    let e = FixedFinger::new(f, volts)?.branch_end()?;
    Ok(BranchLimit { tension: e.tension.to_f32(), joint: e.joint, kind: e.kind })
}
