//! One HV channel's read-back, interpreted: the tick's ADC means as volts and microamps
//! (the monitor calibration), the stack's capacitance estimated from its charge, and the
//! thickness stretch it gives (s = sqrt(C0 / C) for an incompressible film).
//!
//! The estimator (docs/firmware.md "Thickness sensed"): the return current is integrated
//! over windows that close once the voltage has moved [`WINDOW_DV_V`] on a slew, or at each
//! turn of the hold ripple ([`RIPPLE_PP_V`] at [`RIPPLE_PERIOD_MS`]); each window gives
//! Q = C ΔV + I_leak T (ohmic, G ∫V dt, for a held pair): two windows at rates a swing apart both unknowns, a lone swing its capacitance (the
//! leakage known), a slow window its leakage (when its swing's charge is under half its own),
//! each kept as a running mean over the windows.
//! A swing's charge measures the film's dQ/dV; the capacitance kept is its Q/V (the model's
//! incremental ratio taken off).
//!
//! What it is not: the faults that act on these figures (`super::watch`), the loop
//! (`super::hv_loop`).

use crate::board::{ADC_FULL_CODE, BOARD_STACK_C0_PF, IMON_SPAN_UA, IMON_ZERO_CODE, SENSE_STRAY_MIN_PF, SENSE_STRAY_PF, VMON_FULL_SCALE_V};

/// A window closes once the voltage moved this far from its start, V.
pub const WINDOW_DV_V: f32 = 60.0;
/// Or after this long (a hold without ripple: the leakage alone), ms.
pub const WINDOW_MAX_MS: u32 = 400;
/// The hold ripple: peak to peak below the guarded voltage (never above it), V, and its
/// period, ms; only above [`RIPPLE_MIN_V`].
pub const RIPPLE_PP_V: f32 = 100.0;
pub const RIPPLE_PERIOD_MS: u32 = 200;
pub const RIPPLE_MIN_V: f32 = 300.0;
/// The ripple's own rate, V a tick (1 ms): a held channel's ask may move this fast whatever the
/// slew (under a slew of 200 V/s the ripple swung 20 V, its charge under the current sense's
/// resolution: no capacitance measured, a soft film past 2/3 and an open stack unseen).
pub const RIPPLE_STEP_V: f32 = 2.0 * RIPPLE_PP_V / RIPPLE_PERIOD_MS as f32;
/// The most the film's incremental capacitance ratio takes off a swing's capacitance (above
/// it, the sensed film reads thinner than it is, never thicker): the board's film under the
/// hold ceiling stays under 1.15 (1.139 after 10 min at the ceiling; docs/firmware.md
/// "Thickness sensed").
pub const C_RATIO_MAX: f32 = 1.25;
/// The shortest window of a pair, ms (a fast step's few-millisecond windows carry the module's
/// own transient: a pair of them once solved a 0.29 µA leakage on a healthy stack).
pub const PAIR_MIN_MS: f32 = 20.0;
/// Windows with a swing before the capacitance counts as measured.
pub const WINDOWS_TO_MEASURE: u32 = 3;

/// The voltage monitor's calibration: V = gain x code x (full scale / 4095) + offset. A
/// calibration can only tighten: a gain below 1 or an offset below 0 (a monitor that reads
/// low, so the loop would drive the output past what it reads) is refused.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct MonitorCal {
    pub gain: f32,
    pub offset_v: f32,
}

impl MonitorCal {
    pub const NOMINAL: MonitorCal = MonitorCal { gain: 1.0, offset_v: 0.0 };

    /// Accepted only when it reads at or above the nominal chain: gain 1..1.2, offset 0..200 V.
    pub fn checked(gain: f32, offset_v: f32) -> Option<Self> {
        ((1.0..=1.2).contains(&gain) && (0.0..=200.0).contains(&offset_v)).then_some(MonitorCal { gain, offset_v })
    }
}

/// The monitor's code as volts.
pub fn volts_of_code(code: f32, cal: &MonitorCal) -> f32 {
    cal.gain * code * (VMON_FULL_SCALE_V / ADC_FULL_CODE) + cal.offset_v
}

/// The current sense's code as microamps.
pub fn microamps_of_code(code: f32) -> f32 {
    (code - IMON_ZERO_CODE) * (IMON_SPAN_UA / ADC_FULL_CODE)
}

/// One channel's estimate.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Estimator {
    /// The window: its start voltage, the charge so far (nC), its length (ms).
    v0: f32,
    q_nc: f32,
    t_ms: u32,
    /// The window's voltage integral, V ms (the ohmic leakage's charge is G times it).
    s_vms: f32,
    started: bool,
    /// The capacitance the sense sees (pF) and the leakage (µA), each window's estimate
    /// averaged with weights [`C_WEIGHT`] and [`LEAK_WEIGHT`].
    c_pf: f32,
    leak_ua: f32,
    /// The leakage's conductance at its last measure, µA/V (a slew's windows take the
    /// leakage at their voltage from it).
    leak_us_per_v: f32,
    /// The last window that swung: (ΔV, T, Q, its voltage integral), or zeros.
    prev: (f32, f32, f32, f32),
    swings: u32,
    /// Windows that measured the leakage.
    leaks: u32,
    windows: u32,
    /// The last window solved its capacitance jointly with the leakage (a pair): its
    /// capacitance owes nothing to a leakage assumed from before.
    joint: bool,
    /// The last window measured the capacitance (a plausible swing): the thickness is fresh.
    measured: bool,
}

/// Each new window's weight in the capacitance's and the leakage's running means.
pub const C_WEIGHT: f32 = 0.1;
pub const LEAK_WEIGHT: f32 = 0.2;

impl Estimator {
    pub const fn new() -> Self {
        Estimator {
            v0: 0.0,
            q_nc: 0.0,
            t_ms: 0,
            s_vms: 0.0,
            started: false,
            c_pf: BOARD_STACK_C0_PF + SENSE_STRAY_PF,
            leak_ua: 0.0,
            leak_us_per_v: 0.0,
            prev: (0.0, 0.0, 0.0, 0.0),
            swings: 0,
            leaks: 0,
            windows: 0,
            joint: false,
            measured: false,
        }
    }

    /// One tick's mean voltage (V) and return current (µA); `held_ms` how long the channel has
    /// been held (0: not held; held, a window spans one half period of the hold ripple, from
    /// turn to turn, so each swings the ripple's whole [`RIPPLE_PP_V`]); `c_ratio` the film's
    /// incremental capacitance over its capacitance now (`Stacks::incremental_capacitance_ratio`:
    /// a swing's charge measures dQ/dV, the thickness wants Q/V; 1 for none).
    pub fn tick(&mut self, v: f32, i_ua: f32, held_ms: u32, c_ratio: f32) {
        if !(v.is_finite() && i_ua.is_finite()) {
            return;
        }
        let c_ratio = if c_ratio >= 1.0 { c_ratio.min(C_RATIO_MAX) } else { 1.0 };
        if !self.started {
            *self = Estimator { v0: v, started: true, ..*self };
            return;
        }
        self.q_nc += i_ua; // µA x 1 ms = nC
        self.s_vms += v;
        self.t_ms += 1;
        let dv = v - self.v0;
        let turn = held_ms > 0 && ripple_turns(held_ms);
        if (held_ms == 0 && dv.abs() >= WINDOW_DV_V) || (turn && self.t_ms >= 20) || self.t_ms >= WINDOW_MAX_MS {
            self.close(dv, self.t_ms as f32, self.q_nc, self.s_vms, self.v0 + 0.5 * dv, c_ratio);
            self.windows = self.windows.wrapping_add(1);
            self.v0 = v;
            self.q_nc = 0.0;
            self.s_vms = 0.0;
            self.t_ms = 0;
        }
    }

    /// A window of swing `dv` (V), length `t` (ms), charge `q` (nC), voltage integral `s`
    /// (V ms), mean voltage `v_mid`: Q = C ΔV + I_leak T. Two windows in a row whose rates
    /// differ by a swing's (the ripple's up and down; on a slow ramp, the ripple's halves; a
    /// slew's last swing and a hold's slow window) give both unknowns at once, the leakage
    /// ohmic (Q = C ΔV + G S) when both are held above [`RIPPLE_MIN_V`]; a lone swing (a fast
    /// slew) its capacitance with the leakage taken as ohmic from the last measured
    /// conductance; a slow window its leakage. A swing's capacitance is the stack's dQ/dV:
    /// over `c_ratio`, its Q/V.
    fn close(&mut self, dv: f32, t: f32, q: f32, s: f32, v_mid: f32, c_ratio: f32) {
        let c0 = BOARD_STACK_C0_PF + SENSE_STRAY_PF;
        let swing = dv.abs() >= 0.5 * WINDOW_DV_V && t >= 5.0;
        let (pdv, pt, pq, ps) = self.prev;
        let det = dv * pt - pdv * t;
        // two windows at rates far enough apart solve both unknowns: two swings opposite ways
        // (the ripple's up and down), or a swing beside a window that is not one (on a slow
        // ramp, the ripple's halves; a slew's last swing and a hold). Two swings the same way
        // at two rates do not: the monitor's lag on a fast fall solved 143 pF and 0.26 µA on a
        // healthy 73 pF stack
        let pswing = pdv.abs() >= 0.5 * WINDOW_DV_V;
        let rates_apart = (swing && pswing && dv * pdv < 0.0) || (swing != pswing);
        let paired = rates_apart && pt >= PAIR_MIN_MS && t >= PAIR_MIN_MS && det.abs() >= 0.5 * WINDOW_DV_V * (t + pt);
        self.prev = if t >= 5.0 { (dv, t, q, s) } else { (0.0, 0.0, 0.0, 0.0) };
        self.joint = paired;
        let leak_now = self.leak_us_per_v * v_mid;
        let secant = |c_inc: f32| SENSE_STRAY_PF + (c_inc - SENSE_STRAY_PF) / c_ratio;
        // the pair's leakage ohmic (Q = C dV + G S) where both windows are held high enough
        // for their voltage integrals to differ by the ripple alone; else one current
        let det_g = dv * ps - pdv * s;
        let ohmic = paired && s > RIPPLE_MIN_V * t && ps > RIPPLE_MIN_V * pt && det_g.abs() >= 0.5 * WINDOW_DV_V * (s + ps);
        let (c, leak) = if ohmic {
            (secant((q * ps - pq * s) / det_g * 1e3), Some((dv * pq - pdv * q) / det_g * (s / t)))
        } else if paired {
            (secant((q * pt - pq * t) / det * 1e3), Some((dv * pq - pdv * q) / det))
        } else if swing {
            (secant((q - leak_now * t) / dv * 1e3), None)
        } else if t >= 50.0 && !(2.0 * (self.c_pf * 1e-3 * dv).abs() > q.abs()) {
            // a slow window's leakage, unless its swing's charge at the capacitance kept is
            // more than half its own: then the leakage would be that capacitance's error (an
            // open stack's charge taken for a negative leakage, which then cancelled each of
            // its swings' charge: the capacitance never fell to the open stack's)
            (f32::NAN, Some((q - self.c_pf * 1e-3 * dv) / t))
        } else {
            (f32::NAN, None)
        };
        // an outlier (a window cut by a stop, a step) left out, and with a pair's, its leakage;
        // the floor under the least stray, so an open stack's readings (the stray alone, 4 pF
        // at the parts' extreme) all count
        let plausible = c > 0.5 * SENSE_STRAY_MIN_PF && c < 4.0 * c0;
        let leak = if paired && !plausible { None } else { leak };
        self.measured = plausible;
        if plausible {
            self.c_pf += C_WEIGHT * (c - self.c_pf);
            self.swings = self.swings.saturating_add(1);
        }
        if let Some(leak) = leak.filter(|l| l.is_finite()) {
            self.leak_ua += LEAK_WEIGHT * (leak - self.leak_ua);
            self.leaks = self.leaks.saturating_add(1);
            if v_mid > RIPPLE_MIN_V {
                self.leak_us_per_v = self.leak_ua / v_mid;
            }
        }
    }

    /// Windows closed so far.
    pub fn windows(&self) -> u32 {
        self.windows
    }

    /// The last window closed solved the capacitance and the leakage together (a pair); a lone
    /// swing's capacitance carries any leakage that arose since the last measure.
    pub fn last_window_joint(&self) -> bool {
        self.joint
    }

    /// The last window closed measured the capacitance: the thickness now is that window's
    /// (false for a window without a swing: a channel held under the ripple's voltage keeps
    /// the thickness of its last swing, however long ago).
    pub fn last_window_measured(&self) -> bool {
        self.measured
    }

    /// The capacitance the sense sees, pF, once measured.
    pub fn capacitance_pf(&self) -> Option<f32> {
        (self.swings >= WINDOWS_TO_MEASURE).then_some(self.c_pf)
    }

    /// The leakage through the stack, µA, once measured (by its own windows: a leak large
    /// beside the stack's charge leaves the capacitance unmeasured, never the leakage).
    pub fn leakage_ua(&self) -> Option<f32> {
        (self.swings >= WINDOWS_TO_MEASURE || self.leaks >= WINDOWS_TO_MEASURE).then_some(self.leak_ua)
    }

    /// The stack's thickness stretch from its capacitance: sqrt(C0 / (C - stray)), or NaN
    /// before it is measured (or for a capacitance at or below the stray: `super::watch`'s
    /// open stack).
    pub fn thickness_ratio(&self, c0_pf: f32) -> f32 {
        match self.capacitance_pf() {
            Some(c) if c - SENSE_STRAY_PF > 0.0 => libm::sqrtf(c0_pf / (c - SENSE_STRAY_PF)),
            _ => f32::NAN,
        }
    }
}

impl Default for Estimator {
    fn default() -> Self {
        Self::new()
    }
}

/// The hold ripple turns `held_ms` into a hold (a half period ends).
pub fn ripple_turns(held_ms: u32) -> bool {
    held_ms.is_multiple_of(RIPPLE_PERIOD_MS / 2)
}

/// The hold ripple's offset below the guarded voltage `held_ms` into a hold, V (a triangle
/// 0..pp, from 0).
pub fn ripple_v(held_ms: u32) -> f32 {
    let ph = (held_ms % RIPPLE_PERIOD_MS) as f32 / RIPPLE_PERIOD_MS as f32;
    let tri = if ph < 0.5 { 2.0 * ph } else { 2.0 - 2.0 * ph };
    RIPPLE_PP_V * tri
}
