//! The simulated HV plant the firmware is tested against: for each channel the HV module,
//! the divider and the cable, the stack (its own viscoelastic film, C = C0 / s²), leakage,
//! breakdown, and the ADC's quantisation and noise. The host's plant board (`SimBoard::with_plant`),
//! finger-sim and the emulator image run the firmware against it; the board build reads the
//! real ADC instead and never has it.
//!
//! What it is: the physics of docs/firmware.md "The plant", stepped once per 1 ms control
//! tick in [`SUBSTEPS`] electrical sub-steps (one ADC sample each), and the faults the test
//! console injects (`plant film|breakdown|stuck|open|leak|gain|status`).
//!
//! What it is not: the firmware's estimate of any of it (`crate::control::sense`), nor the
//! safety logic. Nothing here is trusted by the control core: it only sees [`HvSense`].

use finger_model::material::{Relaxation, StackLaw, StackState};

use crate::board::{
    HvSense, ADC_FULL_CODE, BOARD_CARD, BOARD_MARGIN, BOARD_STACK_C0_PF, BOARD_Z0_MM, HV_CHANNELS, HV_FULL_SCALE_V, HV_ZERO_DUTY_PCT, IMON_SPAN_UA,
    IMON_ZERO_CODE, SENSE_SAMPLES_PER_TICK, SENSE_STRAY_PF, TRIP_CURRENT_UA, VMON_FULL_SCALE_V,
};

/// Electrical sub-steps (ADC samples) per 1 ms tick.
pub const SUBSTEPS: u32 = SENSE_SAMPLES_PER_TICK;
const DT_S: f32 = 1e-3 / SUBSTEPS as f32;
/// The module's output: a first-order lag (s) and a slew limit (V/s) on its internal
/// source, an output resistor (Ω), a current limit (A, both ways: the bleeder sinks).
const MODULE_TAU_S: f32 = 0.015;
const MODULE_SLEW_V_PER_S: f32 = 150_000.0;
const MODULE_R_OUT_OHM: f32 = 1e6;
const MODULE_I_MAX_A: f32 = 100e-6;
/// The divider's load on the module side (Ω) and the cable's capacitance to its shield (F).
const DIVIDER_OHM: f32 = 1e9;
const CABLE_F: f32 = 50e-12;
/// The film's leakage: V / R0 x exp(E / E_L), R0 for the whole stack (Ω), E_L (V/µm).
const LEAK_R0_OHM: f32 = 1e13;
const LEAK_FIELD_V_PER_UM: f32 = 4.0;
/// A breakdown's short through the stack, Ω (an arc channel burnt through the film).
pub const BREAKDOWN_OHM: f32 = 1e6;
/// ADC noise, LSB rms, on each sample of each reading.
const NOISE_LSB: f32 = 1.0;

/// What the test console can change in a channel.
#[derive(Clone, Copy, Debug, PartialEq)]
pub enum Inject {
    /// A short through the stack; `clears_after_ms`: it burns itself clear (None: it stays).
    Breakdown { clears_after_ms: Option<u32> },
    /// The module's output stuck at this voltage, whatever its control and enable.
    Stuck(f32),
    /// The stack disconnected (a cable off): no capacitance behind the return sense.
    Open,
    /// A leakage resistance across the stack, Ω.
    Leak(f32),
    /// The module's gain, relative to its datasheet (1 nominal).
    Gain(f32),
    /// The voltage monitor's reading stuck at this ADC code.
    MonitorStuck(f32),
}

/// One channel's truth.
#[derive(Clone, Copy, Debug, PartialEq)]
pub struct Truth {
    /// The stack's voltage, V; the current through its return, µA; its thickness stretch.
    pub volts: f32,
    pub current_ua: f32,
    pub s: f32,
    /// The thinnest the film has been, and whether it ever passed its pull-in (collapsed).
    pub s_min: f32,
    pub collapsed: bool,
    /// The highest field across the film so far, V/µm.
    pub field_max_v_per_um: f32,
    /// The stack's capacitance now, as the sense sees it (stack + stray), pF.
    pub c_pf: f32,
}

#[derive(Clone, Copy, Debug)]
struct Channel {
    v_src: f32,
    v: f32,
    state: StackState<f32>,
    s_min: f32,
    collapsed: bool,
    field_max: f32,
    gain: f32,
    stuck: Option<f32>,
    open: bool,
    leak_ohm: f32,
    short_ms: Option<Option<u32>>,
    mon_stuck: Option<f32>,
    i_last: f32,
    /// The film's charge current, A: its capacitance's change over the last tick at its
    /// voltage (V dC/dt), drawn from the node over the next tick.
    i_film: f32,
    /// The analog watchdog cut this channel's module (until the core drops the enable).
    awd_cut: bool,
}

impl Channel {
    fn rest() -> Self {
        Channel {
            v_src: 0.0,
            v: 0.0,
            state: StackState::rest(),
            s_min: 1.0,
            collapsed: false,
            field_max: 0.0,
            gain: 1.0,
            stuck: None,
            open: false,
            leak_ohm: f32::INFINITY,
            short_ms: None,
            mon_stuck: None,
            i_last: 0.0,
            i_film: 0.0,
            awd_cut: false,
        }
    }
}

/// The plant: three channels on one film law, the ADC's noise source, the trip record.
#[derive(Clone, Debug)]
pub struct Plant {
    law: StackLaw<f32>,
    relax: Relaxation<f32>,
    g_eq_mpa: f32,
    time_scale: f32,
    ch: [Channel; HV_CHANNELS],
    /// The true stray the sense sees, pF (the board assumes `SENSE_STRAY_PF`).
    stray_pf: f32,
    /// The divider's true ratio relative to its nominal (resistor tolerance).
    divider_error: f32,
    rng: u32,
    now_us: u64,
    /// A fault injected at this time (µs) and not yet cut.
    pending_since_us: Option<u64>,
    /// Latencies from injection to the enable low, µs: the last and the worst.
    pub trip_last_us: u32,
    pub trip_max_us: u32,
}

/// Why the plant refused a change.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum PlantError {
    /// No such channel (1-based on the console).
    Channel,
    /// The film's modulus: outside 1..100 kPa or not finite.
    Film,
    /// A value not finite or out of its range.
    Value,
}

impl Plant {
    /// The board's film (the card), nominal parts; `seed` for the ADC noise. None when the
    /// board's card gives no law (the core never arms then either).
    pub fn new(seed: u32) -> Option<Self> {
        let law = StackLaw::new(BOARD_CARD, BOARD_Z0_MM, BOARD_MARGIN).ok()?;
        let relax = Relaxation::new(&law, 1e-3).ok()?;
        Some(Plant {
            law,
            relax,
            g_eq_mpa: BOARD_CARD.g_eq_mpa as f32,
            time_scale: 1.0,
            ch: [Channel::rest(); HV_CHANNELS],
            stray_pf: SENSE_STRAY_PF,
            divider_error: 1.0,
            rng: seed | 1,
            now_us: 0,
            pending_since_us: None,
            trip_last_us: 0,
            trip_max_us: 0,
        })
    }

    /// The film's equilibrium modulus, kPa (the branches stay the card's), and how much
    /// faster than real time its branches relax (1: as the card). Keeps each film's state.
    pub fn set_film(&mut self, g_eq_kpa: f32, time_scale: f32) -> Result<(), PlantError> {
        if !(1.0..=100.0).contains(&g_eq_kpa) || !(1.0..=1000.0).contains(&time_scale) {
            return Err(PlantError::Film);
        }
        let eps_r = BOARD_CARD.eps_r as f32;
        let law = StackLaw::with_film(BOARD_CARD, g_eq_kpa * 1e-3, eps_r, BOARD_Z0_MM, BOARD_MARGIN).map_err(|_| PlantError::Film)?;
        self.relax = Relaxation::new(&law, 1e-3 * time_scale).map_err(|_| PlantError::Film)?;
        self.law = law;
        self.g_eq_mpa = g_eq_kpa * 1e-3;
        self.time_scale = time_scale;
        Ok(())
    }

    /// The film's equilibrium modulus, kPa.
    pub fn film_kpa(&self) -> f32 {
        self.g_eq_mpa * 1e3
    }

    /// The stray capacitance the return sense sees (pF) and the divider's ratio error
    /// (relative), as built: what the board's constants do not know.
    pub fn set_parts(&mut self, stray_pf: f32, divider_error: f32) {
        self.stray_pf = stray_pf;
        self.divider_error = divider_error;
    }

    /// A fault or a change into channel `ch` (0-based) now.
    pub fn inject(&mut self, ch: usize, what: Inject) -> Result<(), PlantError> {
        let c = self.ch.get_mut(ch).ok_or(PlantError::Channel)?;
        match what {
            Inject::Breakdown { clears_after_ms } => c.short_ms = Some(clears_after_ms),
            Inject::Stuck(v) if v.is_finite() && (0.0..=12_000.0).contains(&v) => c.stuck = Some(v),
            Inject::Open => c.open = true,
            Inject::Leak(r) if r > 0.0 => c.leak_ohm = r,
            Inject::Gain(g) if g.is_finite() && g > 0.0 && g <= 2.0 => c.gain = g,
            Inject::MonitorStuck(code) if code.is_finite() && (0.0..=ADC_FULL_CODE).contains(&code) => c.mon_stuck = Some(code),
            _ => return Err(PlantError::Value),
        }
        if matches!(what, Inject::Breakdown { .. } | Inject::Stuck(_) | Inject::Open | Inject::Leak(_) | Inject::MonitorStuck(_))
            && self.pending_since_us.is_none()
        {
            self.pending_since_us = Some(self.now_us);
        }
        Ok(())
    }

    /// Time now, µs since the plant started.
    pub fn now_us(&self) -> u64 {
        self.now_us
    }

    /// A fault injected and not yet cut (the enable still high since).
    pub fn fault_pending(&self) -> bool {
        self.pending_since_us.is_some()
    }

    /// Each channel's truth.
    pub fn truth(&self) -> [Truth; HV_CHANNELS] {
        let mut t = [Truth { volts: 0.0, current_ua: 0.0, s: 1.0, s_min: 1.0, collapsed: false, field_max_v_per_um: 0.0, c_pf: 0.0 }; HV_CHANNELS];
        for (k, c) in self.ch.iter().enumerate() {
            t[k] = Truth {
                volts: c.v,
                current_ua: c.i_last * 1e6,
                s: c.state.s,
                s_min: c.s_min,
                collapsed: c.collapsed,
                field_max_v_per_um: c.field_max,
                c_pf: self.stack_f(c) * 1e12 + self.stray_pf,
            };
        }
        t
    }

    fn stack_f(&self, c: &Channel) -> f32 {
        if c.open {
            0.0
        } else {
            BOARD_STACK_C0_PF * 1e-12 / (c.state.s * c.state.s)
        }
    }

    /// A standard normal deviate (Irwin-Hall of four uniforms; xorshift32).
    fn gauss(&mut self) -> f32 {
        let mut sum = 0.0;
        for _ in 0..4 {
            self.rng ^= self.rng << 13;
            self.rng ^= self.rng >> 17;
            self.rng ^= self.rng << 5;
            sum += (self.rng >> 8) as f32 * (1.0 / 16_777_216.0);
        }
        (sum - 2.0) * 1.732_050_8
    }

    /// One 1 ms tick with the board's outputs held: `duty` of `max_duty` per channel and
    /// the enable. Returns the tick's averaged read-back, the analog watchdog's trip in it.
    pub fn tick(&mut self, duty: [u16; HV_CHANNELS], max_duty: u16, enable: bool) -> HvSense {
        let mut sense = HvSense::default();
        let z = HV_ZERO_DUTY_PCT / 100.0;
        let trip_code = IMON_ZERO_CODE + TRIP_CURRENT_UA / IMON_SPAN_UA * ADC_FULL_CODE;
        if !enable {
            for c in self.ch.iter_mut() {
                c.awd_cut = false;
            }
            self.record_cut();
        } else if self.ch.iter().all(|c| c.awd_cut) {
            // the analog watchdog's latch still holds every module off (the enable was not low
            // for a tick since it tripped): a fault injected meanwhile finds the supply cut
            self.record_cut();
        }
        for _ in 0..SUBSTEPS {
            self.now_us += (DT_S * 1e6) as u64;
            for k in 0..HV_CHANNELS {
                let frac = duty[k] as f32 / max_duty.max(1) as f32;
                let mut c = self.ch[k];
                let on = enable && !c.awd_cut;
                let ctrl = if on && frac > z { (frac - z) / (1.0 - z) * HV_FULL_SCALE_V * c.gain } else { 0.0 };
                let want = c.stuck.unwrap_or(ctrl);
                let lag = (want - c.v_src) * (DT_S / MODULE_TAU_S);
                let max_step = MODULE_SLEW_V_PER_S * DT_S;
                c.v_src += lag.clamp(-max_step, max_step);
                let c_stack = self.stack_f(&c);
                let thick_um = c.state.s * BOARD_Z0_MM * 1e3;
                let field = if thick_um > 0.0 { c.v / thick_um } else { 0.0 };
                let mut g_stack = 0.0;
                if !c.open {
                    g_stack += libm::expf(field / LEAK_FIELD_V_PER_UM) / LEAK_R0_OHM + 1.0 / c.leak_ohm;
                    if c.short_ms.is_some() {
                        g_stack += 1.0 / BREAKDOWN_OHM;
                    }
                }
                let stray_f = self.stray_pf * 1e-12;
                let c_node = c_stack + CABLE_F + stray_f;
                // the node by backward Euler (stable whatever the short), the module's
                // current limited
                let g_load = 1.0 / DIVIDER_OHM + g_stack;
                let mut v_new = (c_node * c.v + DT_S * (c.v_src / MODULE_R_OUT_OHM - c.i_film)) / (c_node + DT_S * (1.0 / MODULE_R_OUT_OHM + g_load));
                let i_src = (c.v_src - v_new) / MODULE_R_OUT_OHM;
                if !(i_src.abs() <= MODULE_I_MAX_A) {
                    let i_lim = MODULE_I_MAX_A.copysign(i_src);
                    v_new = (c_node * c.v + DT_S * (i_lim - c.i_film)) / (c_node + DT_S * g_load);
                }
                let v_new = v_new.max(0.0);
                let dv = v_new - c.v;
                let i_stack_dc = v_new * g_stack;
                c.v = v_new;
                // the return sees the stack's charge and conduction and the stray beside it
                let i_sense = (c_stack + stray_f) * dv / DT_S + c.i_film + i_stack_dc;
                c.i_last = i_sense;
                let v_code = match c.mon_stuck {
                    Some(code) => code,
                    None => libm::roundf(c.v * self.divider_error / VMON_FULL_SCALE_V * ADC_FULL_CODE + NOISE_LSB * self.gauss()).clamp(0.0, ADC_FULL_CODE),
                };
                let i_code = libm::roundf(IMON_ZERO_CODE + i_sense * 1e6 / IMON_SPAN_UA * ADC_FULL_CODE + NOISE_LSB * self.gauss()).clamp(0.0, ADC_FULL_CODE);
                sense.v_code[k] += v_code / SUBSTEPS as f32;
                sense.i_code[k] += i_code / SUBSTEPS as f32;
                if i_code >= trip_code && on {
                    // the analog watchdog: its interrupt drops the enable (all channels)
                    sense.trip.get_or_insert(k as u8);
                }
                self.ch[k] = c;
            }
            if sense.trip.is_some() {
                for c in self.ch.iter_mut() {
                    c.awd_cut = true;
                }
                self.record_cut();
            }
        }
        for k in 0..HV_CHANNELS {
            let mut c = self.ch[k];
            let v = c.v;
            let c_before = self.stack_f(&c);
            if !c.collapsed && c.state.advance(&self.law, &self.relax, v).is_err() {
                // past its pull-in the film collapses: it breaks down
                c.collapsed = true;
                c.short_ms = Some(None);
            }
            // Q = C V: the film's thinning at its voltage draws V dC over the next tick
            c.i_film = v * (self.stack_f(&c) - c_before) * 1e3;
            c.s_min = c.s_min.min(c.state.s);
            let thick_um = c.state.s * BOARD_Z0_MM * 1e3;
            c.field_max = c.field_max.max(v / thick_um);
            if let Some(Some(ms)) = c.short_ms {
                c.short_ms = if ms <= 1 { None } else { Some(Some(ms - 1)) };
            }
            self.ch[k] = c;
        }
        sense
    }

    /// The module is cut now (the enable low, or the analog watchdog).
    fn record_cut(&mut self) {
        if let Some(t0) = self.pending_since_us.take() {
            let lat = self.now_us.saturating_sub(t0) as u32;
            self.trip_last_us = lat;
            self.trip_max_us = self.trip_max_us.max(lat);
        }
    }
}
