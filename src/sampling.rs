//! The board's HV read-back sampling, its arithmetic: the layout of the DMA buffer that
//! ADC1 and ADC2 fill in dual simultaneous mode, the half/full bookkeeping of the tick that
//! reads it, the tick's means ([`HvSense`]), the analog watchdog's threshold codes from the
//! board constants, and which channel a watchdog trip came from.
//!
//! Pure: the registers are `chip::hv_adc` (board build only); the host tests check this
//! (host-tests/tests/hv_sampling.rs). Not here: what the means mean (`control::sense`).
//!
//! Layout: each TIM2 trigger converts the three channels in scan; each conversion pair is
//! one 32-bit word of ADC_CDR, ADC1's code (the return current) in bits 0..11 and ADC2's (the
//! voltage monitor) in bits 16..27, channel k at word index 3g + k. The buffer holds two
//! halves of one tick's samples each, DMA2 stream 0 circular over both.

use crate::board::{
    HvSense, ADC_FULL_CODE, HV_CHANNELS, HV_LIMIT_V, IMON_SPAN_UA, IMON_ZERO_CODE, OVER_FRAC, OVER_V, SENSE_SAMPLES_PER_TICK, TRIP_CURRENT_UA,
    VMON_FULL_SCALE_V,
};

/// Words of one tick's samples (one half of the buffer).
pub const HALF_WORDS: usize = SENSE_SAMPLES_PER_TICK as usize * HV_CHANNELS;
/// Words of the whole circular buffer (NDTR's reload).
pub const BUF_WORDS: usize = 2 * HALF_WORDS;
/// Ticks in a row without a half completed before the readings go NaN (the `sensor` fault:
/// the timer, the ADC or the DMA stopped).
pub const STALE_LIMIT: u32 = 3;

/// The current code (ADC1) and the voltage code (ADC2) of one word.
pub fn split(word: u32) -> (u16, u16) {
    ((word & 0x0FFF) as u16, ((word >> 16) & 0x0FFF) as u16)
}

/// The word index the DMA writes next, from NDTR (the transfers left before the reload).
pub fn writing_at(ndtr: u32) -> usize {
    let n = (ndtr as usize).min(BUF_WORDS);
    (BUF_WORDS - n) % BUF_WORDS
}

/// The last [`SENSE_SAMPLES_PER_TICK`] whole groups before the DMA's position `at`, each
/// channel's mean (voltage codes, current codes); `word(i)` reads buffer word i.
pub fn window_means(at: usize, word: impl Fn(usize) -> u32) -> ([f32; HV_CHANNELS], [f32; HV_CHANNELS]) {
    let end = at - at % HV_CHANNELS;
    let (mut v, mut i) = ([0u32; HV_CHANNELS], [0u32; HV_CHANNELS]);
    for n in 0..HALF_WORDS {
        let idx = (end + BUF_WORDS - HALF_WORDS + n) % BUF_WORDS;
        let (ic, vc) = split(word(idx));
        v[idx % HV_CHANNELS] += vc as u32;
        i[idx % HV_CHANNELS] += ic as u32;
    }
    let k = 1.0 / SENSE_SAMPLES_PER_TICK as f32;
    (v.map(|s| s as f32 * k), i.map(|s| s as f32 * k))
}

/// The DMA's half-transfer and transfer-complete flags as the tick read them (HTIF0, TCIF0).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct HalfFlags {
    pub half: bool,
    pub full: bool,
}

/// The tick's bookkeeping of the halves: how many ticks saw no half complete (stale), how
/// many saw both (a half no tick read).
#[derive(Clone, Copy, Debug, Default, PartialEq, Eq)]
pub struct Halves {
    stale_run: u32,
    pub stale_ticks: u32,
    pub missed_halves: u32,
    pub ticks: u32,
}

impl Halves {
    pub const fn new() -> Self {
        Halves { stale_run: 0, stale_ticks: 0, missed_halves: 0, ticks: 0 }
    }

    /// One tick: the flags seen since the last, the DMA's position `at` and its buffer; the
    /// tick's read-back. The means are of the last tick's worth of samples before `at`
    /// whatever the phase of the halves against the tick; the flags say the DMA still runs:
    /// [`STALE_LIMIT`] ticks in a row with neither flag give NaN readings.
    pub fn sense(&mut self, flags: HalfFlags, at: usize, word: impl Fn(usize) -> u32, trip: Option<u8>) -> HvSense {
        self.ticks = self.ticks.wrapping_add(1);
        if flags.half || flags.full {
            self.stale_run = 0;
        } else {
            self.stale_run = self.stale_run.saturating_add(1);
            self.stale_ticks = self.stale_ticks.wrapping_add(1);
        }
        if flags.half && flags.full {
            self.missed_halves = self.missed_halves.wrapping_add(1);
        }
        let (v_code, i_code) = if self.stale_run >= STALE_LIMIT { ([f32::NAN; HV_CHANNELS], [f32::NAN; HV_CHANNELS]) } else { window_means(at, word) };
        HvSense { v_code, i_code, trip }
    }
}

/// The analog watchdogs' thresholds, ADC codes (ADC_HTR, ADC_LTR: the watchdog flags a
/// conversion above HTR or below LTR).
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub struct AwdCodes {
    /// ADC1 (the return currents): past +[`TRIP_CURRENT_UA`] (a breakdown) or past
    /// -[`TRIP_CURRENT_UA`] (the stack's voltage collapsing faster than the module's own fall
    /// can pull it: a short ahead of the stack).
    pub current_high: u16,
    pub current_low: u16,
    /// ADC2 (the voltage monitors): past the board's hard limit by the over-ceiling bound
    /// (`board::OVER_FRAC`, `OVER_V`); below: never.
    pub volts_high: u16,
}

/// The code a watchdog's HTR holds so that it flags exactly the codes at or above `trip`
/// (the plant's and the tick's `>=`), kept below the rail (a code at the rail flags too).
fn htr_for(trip: f32) -> u16 {
    let c = libm::ceilf(trip) - 1.0;
    c.clamp(0.0, ADC_FULL_CODE - 1.0) as u16
}

/// The threshold codes from the board constants.
pub fn awd_codes() -> AwdCodes {
    let span = TRIP_CURRENT_UA / IMON_SPAN_UA * ADC_FULL_CODE;
    let low_trip = IMON_ZERO_CODE - span;
    let over_v = HV_LIMIT_V * (1.0 + OVER_FRAC) + OVER_V;
    AwdCodes {
        current_high: htr_for(IMON_ZERO_CODE + span),
        // flags the codes at or below the mirror of the high trip: LTR = floor + 1
        current_low: (libm::floorf(low_trip) + 1.0).clamp(1.0, ADC_FULL_CODE) as u16,
        volts_high: htr_for(over_v / VMON_FULL_SCALE_V * ADC_FULL_CODE),
    }
}

/// The channel a watchdog trip came from: the newest sample out of its window among the
/// last two groups before the DMA's position `at`; else (the sample not yet moved by the
/// DMA) the channel whose current is farthest from zero in the last group.
pub fn trip_channel(at: usize, word: impl Fn(usize) -> u32, codes: &AwdCodes) -> u8 {
    let idx = |back: usize| (at + BUF_WORDS - back) % BUF_WORDS;
    for back in 1..=2 * HV_CHANNELS {
        let w = idx(back);
        let (ic, vc) = split(word(w));
        if ic > codes.current_high || ic < codes.current_low || vc > codes.volts_high {
            return (w % HV_CHANNELS) as u8;
        }
    }
    let mut best = (0u8, 0i32);
    for back in 1..=HV_CHANNELS {
        let w = idx(back);
        let d = (split(word(w)).0 as i32 - IMON_ZERO_CODE as i32).abs();
        if d >= best.1 {
            best = ((w % HV_CHANNELS) as u8, d);
        }
    }
    best.0
}
