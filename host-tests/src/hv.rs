//! The control core's stacks in time, on the simulated board: a voltage step on one channel
//! from rest, plain or shaped, and its settling time to 1 % of the target's thickness. Shared
//! by tests/hv_in_time.rs and the `hv_settle` example (docs/firmware.md's settling figures).
use finger_fw::control::{Control, Setpoints};
use finger_fw::sim::SimBoard;

/// Armed setpoints for `target` (V), plain or `shaped`, at `slew` V/s.
pub fn setpoints(c: &Control<SimBoard>, target: [f32; 3], shaped: bool, slew: f32) -> Setpoints {
    let v = c.view();
    Setpoints { seq: v.seq + 1, epoch: v.epoch, armed: true, target_v: target, servo_duty: 2000, servo_released: 2000, duty_ceiling: [8400; 3], slew, shaped }
}

/// A step to `volts` on channel 1 from rest at `slew` V/s, `secs` long: the predicted
/// thickness stretch and the voltage after each 1 ms tick.
pub fn step_response(volts: f32, shaped: bool, slew: f32, secs: u32) -> Vec<(f32, f32)> {
    let mut c = Control::new(SimBoard::default(), 2000, slew);
    assert!(c.apply(&setpoints(&c, [volts, 0.0, 0.0], shaped, slew)));
    assert_eq!(c.view().fault, None, "{volts} V refused");
    (0..secs * 1000)
        .map(|_| {
            c.tick(c.now_ms());
            let v = c.view();
            (v.stack_ratio[0], v.volts[0])
        })
        .collect()
}

/// Settling time to within 1 % of the target thickness `s_target`, s: from the step to the
/// tick from which the thickness stays within 1 % (None: not settled within the run).
pub fn settling_s(s: &[(f32, f32)], s_target: f32) -> Option<f64> {
    let out = |x: f32| (x - s_target).abs() > 0.01 * s_target;
    if s.last().map(|l| out(l.0)).unwrap_or(true) {
        return None;
    }
    Some(s.iter().rposition(|x| out(x.0)).map(|i| (i + 1) as f64 / 1000.0).unwrap_or(0.0))
}
