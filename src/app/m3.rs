//! The Cortex-M3 image's model calls (`cfg(m3)`, docs/firmware.md "Cortex-M3 image"): the
//! console's forward solves (`solve`, `status`, the servo plan) and fmax on the fixed-point
//! model (`finger_model::fixed`, docs/fixed-point.md) instead of the f32 model in soft float.
//! The set-up (compliances at the voltages) is the f32 model's; the solve has no float
//! operation; `solve`'s tip stiffness from the converged fixed-point state, once in f32.
//! `pose` on the fixed-point inverse, at a given tension or at the F405's tension rule.

use finger_model::fixed::q::{Nt, Rad};
use finger_model::fixed::{FixedFinger, FixedInverseDirect, FixedSolution};
use finger_model::mat3::Mat3;
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
    let mut ff = FixedFinger::empty();
    ff.prepare(f, volts)?;
    solved(f, &ff.solve(Nt::from_f32(p))?, volts)
}

/// [`forward`] and the tip stiffness at its posture (`solve`): the fixed-point state's
/// sub-element displacements, then K_tip = (Σ J C Jᵀ)⁻¹ once in f32 (`FixedFinger::tip_stiffness`).
#[inline(never)]
pub(super) fn forward_stiffness(f: &Finger<f32>, p: f32, volts: &[f32; CHANNELS]) -> Result<(Solved, Mat3<f32>), ModelError> {
    let mut ff = FixedFinger::empty();
    ff.prepare(f, volts)?;
    let s = ff.solve(Nt::from_f32(p))?;
    Ok((solved(f, &s, volts)?, stiffness(f, &ff, &s)?))
}

#[inline(never)]
fn stiffness(f: &Finger<f32>, ff: &FixedFinger, s: &FixedSolution) -> Result<Mat3<f32>, ModelError> {
    ff.tip_stiffness(f, s)
}

fn solved(f: &Finger<f32>, s: &FixedSolution, volts: &[f32; CHANNELS]) -> Result<Solved, ModelError> {
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
    let mut ff = FixedFinger::empty();
    ff.prepare(f, volts)?;
    let e = ff.branch_end()?;
    Ok(BranchLimit { tension: e.tension.to_f32(), joint: e.joint, kind: e.kind })
}

#[cfg(feature = "pose")]
compile_error!("the Cortex-M3 image's pose is the fixed-point one (app/m3.rs): build it without feature pose");

impl Commands {
    /// `pose <d1> <d2> <d3> [<P>]` on the fixed-point inverse (`FixedInverseDirect`, the
    /// ceiling in force, the top voltage the F405's: `Options::top` of it): at the given
    /// tension, or without `<P>` at the F405's tension rule (the midpoint of the tensions that
    /// hold the posture, `solve_free`). The voltages, then, armed, the checks of `volt` and
    /// `force` ([`Commands::plan_setpoints`]) and the outputs move; disarmed nothing moves.
    /// Reply `ok force= volts= joints=` (joints: the fixed-point forward solve at that answer),
    /// and without `<P>` `range=` (the interval, as the F405's).
    #[inline(never)]
    pub(super) fn cmd_pose(&mut self, args: &[&[u8]], r: &mut Reply) -> Result<(), CmdError> {
        if args.len() != 3 && args.len() != 4 {
            return Err(err!("usage"; "pose <d1> <d2> <d3> [<P>]"));
        }
        let mut rad = [Rad::ZERO; CHANNELS];
        for ch in 0..CHANNELS {
            let d = number(args[ch], "angle")?;
            if !(d.abs() <= 360.0) {
                return Err(err!("usage"; "pose: joint angles are degrees, |d| <= 360"));
            }
            rad[ch] = Rad::from_f32(d / DEG);
        }
        let given = match args.get(3) {
            Some(t) => Some(tension(number(t, "P")?)?),
            None => None,
        };
        let mut ff = FixedFinger::empty();
        ff.prepare(&self.finger, &[0.0; CHANNELS]).map_err(model_err)?;
        let top = finger_model::inverse::Options::<f32>::default().top;
        let inv = FixedInverseDirect::new(&self.finger, &ff, self.vmax[0] * top).map_err(model_err)?;
        let mut at = Nt::from_f32(given.unwrap_or(0.0));
        let res = match given {
            Some(_) => inv.solve(&rad, at).map(|s| (s, None)),
            None => inv.solve_free(&rad, &mut at).map(|(s, i)| (s, Some(i))),
        };
        let (sol, range) = res.map_err(|e| match e {
            // the fixed-point inverse's range is in joint angles (the f32 one's in compliance)
            ModelError::Unreachable { joint, needed, min, max } => {
                let d = |x: f64| Fixed(x as f32 * DEG, 3);
                err!("unreachable"; "joint ", joint, ": needs ", d(needed), " deg, its stack spans ", d(min), "..", d(max), " deg at ", Fixed(at.to_f32(), 3), " N")
            }
            e => model_err(e),
        })?;
        let p = sol.tension.to_f32();
        let v = inv.volts(&sol).map_err(model_err)?;
        let target = [v[0], v[1], v[2]];
        // the ceilings as `volt` checks them, armed or not; 0 V (rest thickness) is off
        self.check_volts_of(&target, true)?;
        let held = forward(&self.finger, p, &target).map_err(model_err)?;
        if self.armed {
            self.require_armed("pose")?;
            let (cable, sdeg) = self.plan_setpoints(p, &target)?;
            self.target_v = target;
            self.force = p;
            self.cable = cable;
            self.set_servo(sdeg);
        }
        let _ = w!(r; "force=", Fixed(p, 4), " volts=");
        list(r, &target, 1);
        let _ = w!(r; " joints=");
        joints(r, &held);
        if let Some(i) = range {
            let _ = w!(r; " range=", Fixed(i[0].to_f32(), 4), ",", Fixed(i[1].to_f32(), 4));
        }
        Ok(())
    }
}
