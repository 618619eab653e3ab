//! A stack the HV sense sees, written synthetically: its current from i = C dv/dt + G v + I0
//! tick by tick, fed to the estimator (`finger_fw::control::sense::Estimator`) on the paths the
//! core drives (a held channel's ripple, a slew). What the estimator and watch tests share.
use finger_fw::control::sense::{ripple_v, Estimator, RIPPLE_MIN_V};

/// A stack the sense sees: capacitance (pF, the stray included), ohmic leakage (µA/V) and a
/// constant leakage (µA); it answers each tick's voltage with that tick's current. Its voltage
/// is read exactly, or through a monitor that lags it ([`Stack::with_monitor_lag`]).
pub struct Stack {
    pub c_pf: f32,
    pub g_ua_per_v: f32,
    pub i0_ua: f32,
    v_before: Option<f32>,
    /// The monitor's first-order lag, ms (0: none), and its reading.
    monitor_lag_ms: f32,
    v_read: f32,
}

impl Stack {
    pub fn new(c_pf: f32, g_ua_per_v: f32, i0_ua: f32) -> Self {
        Stack { c_pf, g_ua_per_v, i0_ua, v_before: None, monitor_lag_ms: 0.0, v_read: 0.0 }
    }

    /// The same stack, its voltage read through a first-order lag of `ms` (a divider's RC; 0:
    /// none, else >= 1): the current is the stack's, the voltage the estimator sees is late.
    pub fn with_monitor_lag(self, ms: f32) -> Self {
        Stack { monitor_lag_ms: ms, ..self }
    }

    /// One 1 ms tick at `v` into `est`; `held_ms` as the core passes it.
    pub fn tick(&mut self, est: &mut Estimator, v: f32, held_ms: u32, c_ratio: f32) {
        let (v_before, read_before) = match self.v_before {
            Some(b) => (b, self.v_read),
            None => (v, v),
        };
        self.v_before = Some(v);
        self.v_read = if self.monitor_lag_ms > 0.0 { read_before + (v - read_before) / self.monitor_lag_ms } else { v };
        est.tick(self.v_read, self.c_pf * (v - v_before) * 1e-3 + self.g_ua_per_v * v + self.i0_ua, held_ms, c_ratio);
    }

    /// Held at `guard_v` drifting `drift_v_per_ms`, rippled below it as the core does, for `ms`.
    pub fn hold(&mut self, est: &mut Estimator, guard_v: f32, drift_v_per_ms: f32, ms: u32) -> f32 {
        let mut v = guard_v;
        for held_ms in 1..=ms {
            let top = guard_v + drift_v_per_ms * held_ms as f32;
            v = if top > RIPPLE_MIN_V { top - ripple_v(held_ms) } else { top };
            self.tick(est, v, held_ms, 1.0);
        }
        v
    }

    /// A slew (not held) from `from_v` to `to_v` at `v_per_ms`.
    pub fn slew(&mut self, est: &mut Estimator, from_v: f32, to_v: f32, v_per_ms: f32) {
        let n = ((to_v - from_v).abs() / v_per_ms) as u32;
        for k in 1..=n {
            self.tick(est, from_v + (to_v - from_v) * k as f32 / n as f32, 0, 1.0);
        }
    }
}
