//! The board build's read-back sampling arithmetic (src/sampling.rs; its registers are
//! src/chip/hv_adc.rs, which no test here runs: QEMU does not model the F405's ADC): the DMA
//! buffer's means at any phase of the halves against the tick, the halves' bookkeeping and the
//! stale cut-off, the analog watchdog's threshold codes against the plant's and the tick's
//! bounds, and the trip's channel.
use finger_fw::board::{
    ADC_BITS, ADC_FULL_CODE, ADC_VREF_V, HV_CHANNELS, HV_LIMIT_V, IMON_GAIN, IMON_SENSE_OHM, IMON_SPAN_UA, IMON_ZERO_CODE, SENSE_SAMPLES_PER_TICK,
    TRIP_CURRENT_UA,
};
use finger_fw::control::sense::{microamps_of_code, volts_of_code, MonitorCal};
use finger_fw::control::watch::{OVER_FRAC, OVER_V};
use finger_fw::sampling::{awd_codes, split, trip_channel, window_means, writing_at, HalfFlags, Halves, BUF_WORDS, HALF_WORDS, STALE_LIMIT};

/// One DMA word: ADC1's current code low, ADC2's voltage code high.
fn pair(i_code: u16, v_code: u16) -> u32 {
    i_code as u32 | (v_code as u32) << 16
}

/// A simulated chain: the DMA writes one word per conversion pair into the circular buffer,
/// HTIF at the half, TCIF at the end, as DMA2 stream 0 does.
struct Dma {
    buf: [u32; BUF_WORDS],
    at: usize,
    flags: HalfFlags,
}

impl Dma {
    fn new() -> Self {
        Dma { buf: [0; BUF_WORDS], at: 0, flags: HalfFlags::default() }
    }
    fn push(&mut self, w: u32) {
        self.buf[self.at] = w;
        self.at = (self.at + 1) % BUF_WORDS;
        if self.at == HALF_WORDS {
            self.flags.half = true;
        }
        if self.at == 0 {
            self.flags.full = true;
        }
    }
    /// NDTR as the stream reports it (transfers left before the reload).
    fn ndtr(&self) -> u32 {
        (BUF_WORDS - self.at) as u32
    }
    fn take_flags(&mut self) -> HalfFlags {
        core::mem::take(&mut self.flags)
    }
}

#[test]
fn the_layout_is_adc1_low_adc2_high_and_ndtr_counts_down() {
    assert_eq!(split(pair(0x0ABC, 0x0123)), (0x0ABC, 0x0123));
    // the 12 data bits only (DATA1, DATA2 right aligned)
    assert_eq!(split(0xF123_F456), (0x0456, 0x0123));
    assert_eq!(writing_at(BUF_WORDS as u32), 0);
    assert_eq!(writing_at(1), BUF_WORDS - 1);
    assert_eq!(writing_at(BUF_WORDS as u32 - 7), 7);
    assert_eq!(HALF_WORDS, SENSE_SAMPLES_PER_TICK as usize * HV_CHANNELS);
}

/// The DMA runs at 10 kHz, the tick at 1 kHz, at every phase between them (the trigger's
/// sample k of the tick, and the word of a group the DMA is in): each tick's means are
/// exactly the last 10 samples of each channel.
#[test]
fn each_tick_averages_the_last_tick_of_samples_at_every_phase() {
    for phase in 0..HALF_WORDS {
        let mut dma = Dma::new();
        let mut halves = Halves::new();
        let mut n = 0u32;
        // sample g of channel k: a ramp distinct per channel
        let code = |g: u32, k: usize| -> (u16, u16) { ((1000 + 7 * g + 300 * k as u32) as u16 % 4096, (200 + 13 * g + 500 * k as u32) as u16 % 4096) };
        for _ in 0..phase {
            let (i, v) = code(n / 3, (n % 3) as usize);
            dma.push(pair(i, v));
            n += 1;
        }
        for tick in 0..50 {
            for _ in 0..HALF_WORDS {
                let (i, v) = code(n / 3, (n % 3) as usize);
                dma.push(pair(i, v));
                n += 1;
            }
            if tick < 2 {
                continue;
            }
            let flags = dma.take_flags();
            let at = writing_at(dma.ndtr());
            let s = halves.sense(flags, at, |w| dma.buf[w], None);
            let last_group = n / 3; // groups complete so far
            for k in 0..HV_CHANNELS {
                let (mut si, mut sv) = (0.0, 0.0);
                for g in last_group - 10..last_group {
                    let (i, v) = code(g, k);
                    si += i as f32;
                    sv += v as f32;
                }
                assert!((s.i_code[k] - si / 10.0).abs() < 1e-3, "phase {phase} tick {tick} ch {k}: {} against {}", s.i_code[k], si / 10.0);
                assert!((s.v_code[k] - sv / 10.0).abs() < 1e-3, "phase {phase} tick {tick} ch {k}: {} against {}", s.v_code[k], sv / 10.0);
            }
        }
        assert_eq!(halves.stale_ticks, 0, "phase {phase}");
    }
}

/// A chain that stops (the timer, the ADC's overrun, the DMA): the readings go NaN after
/// STALE_LIMIT ticks with no half completed, which the tick's checks latch as `sensor`; a
/// tick seeing both halves counts a half no tick read.
#[test]
fn a_stopped_chain_reads_nan_after_the_stale_limit() {
    let buf = [pair(2048, 1000); BUF_WORDS];
    let mut h = Halves::new();
    let fresh = HalfFlags { half: true, full: false };
    assert!(h.sense(fresh, 0, |w| buf[w], None).v_code[0] == 1000.0);
    for k in 1..STALE_LIMIT {
        let s = h.sense(HalfFlags::default(), 0, |w| buf[w], None);
        assert!(s.v_code[0].is_finite(), "stale tick {k}: one late half is not a fault");
    }
    let s = h.sense(HalfFlags::default(), 0, |w| buf[w], None);
    assert!(s.v_code.iter().chain(s.i_code.iter()).all(|c| c.is_nan()));
    assert_eq!(h.stale_ticks, STALE_LIMIT);
    // the chain back: readings again
    let s = h.sense(HalfFlags { half: true, full: true }, 0, |w| buf[w], Some(1));
    assert_eq!((s.v_code[2], s.i_code[1], s.trip), (1000.0, 2048.0, Some(1)));
    assert_eq!(h.missed_halves, 1);
    // a NaN reading is a sensor fault at the tick's checks
    let mut w = finger_fw::control::watch::Watch::new();
    let r = finger_fw::control::watch::Reading { v: f32::NAN, i_ua: f32::NAN, v_code: f32::NAN };
    assert_eq!(
        w.check(&r, 1000.0, &finger_fw::control::hv_loop::Ask::ZERO, 5000.0, true, &finger_fw::control::sense::Estimator::new()),
        Some(finger_fw::control::Fault::Sensor)
    );
}

/// The watchdog flags a code above HTR or below LTR (RM0090): exactly the codes the plant's
/// watchdog and the tick's check trip on, for every code.
#[test]
fn the_watchdog_codes_trip_where_the_plant_and_the_tick_do() {
    let c = awd_codes();
    let plant_trip = IMON_ZERO_CODE + TRIP_CURRENT_UA / IMON_SPAN_UA * ADC_FULL_CODE;
    for code in 0..=4095u16 {
        let hw_high = code > c.current_high;
        assert_eq!(hw_high, code as f32 >= plant_trip, "code {code}: the plant's watchdog");
        // the tick's check: a current past TRIP_CURRENT_UA (a code past the high threshold is one)
        if hw_high {
            assert!(microamps_of_code(code as f32) >= TRIP_CURRENT_UA - 1e-3);
        } else {
            assert!(microamps_of_code(code as f32) < TRIP_CURRENT_UA);
        }
        let hw_low = code < c.current_low;
        assert_eq!(hw_low, microamps_of_code(code as f32) <= -TRIP_CURRENT_UA + 1e-3, "code {code}: the mirror");
        let v = volts_of_code(code as f32, &MonitorCal::NOMINAL);
        let over = HV_LIMIT_V * (1.0 + OVER_FRAC) + OVER_V;
        assert_eq!(code > c.volts_high, v >= over - 0.01, "code {code} ({v} V): over the hard limit's bound");
    }
    // a healthy charge at the module's own slew (24 µA at the 2/3 limit) never trips
    let at_slew = (IMON_ZERO_CODE + 24.0 / IMON_SPAN_UA * ADC_FULL_CODE) as u16;
    assert!(at_slew <= c.current_high && (4096 - at_slew) >= c.current_low);
}

/// The number just before `unit` (or just after `word`) in `text`.
fn number_near(text: &str, at: usize, forward: bool) -> f64 {
    let digit = |c: char| c.is_ascii_digit() || c == '.' || c == ',';
    let s: String = if forward {
        text[at..].chars().skip_while(|c| *c == ' ').take_while(|&c| digit(c)).collect()
    } else {
        let rev: String = text[..at].chars().rev().skip_while(|c| *c == ' ').take_while(|&c| digit(c)).collect();
        rev.chars().rev().collect()
    };
    s.replace(',', "").parse().unwrap_or_else(|_| panic!("no number near {:?}", &text[at.saturating_sub(20)..(at + 20).min(text.len())]))
}

/// The return-current chain as docs/firmware.md documents its parts (the sense resistor and
/// its gain, in the hardware table) with the ADC's reference and bits: the span they give, and
/// the watchdog's codes from it, are the board's constants and the codes written to ADC1; a
/// charge at the module's own slew stays inside them; the docs state the codes the code
/// computes. (A board built to a gain of 1.65 with a 100 µA span read currents 2x high and
/// tripped at a real 15 µA.)
#[test]
fn the_current_chain_codes_follow_from_the_documented_parts() {
    let doc = std::fs::read_to_string(concat!(env!("CARGO_MANIFEST_DIR"), "/../docs/firmware.md")).unwrap();
    let row = doc.lines().find(|l| l.starts_with("| return current")).expect("docs/firmware.md: the return current's row");
    let r_ohm = number_near(row, row.find(" kΩ").expect("the sense resistor, kΩ"), false) * 1e3;
    let gain = number_near(row, row.find("gain ").expect("the gain") + 5, true);
    assert_eq!((r_ohm as f32, gain as f32), (IMON_SENSE_OHM, IMON_GAIN), "the documented parts are the board's");
    let (vref, bits) = (ADC_VREF_V as f64, ADC_BITS);
    let full = ((1u32 << bits) - 1) as f64;
    let zero = (1u32 << (bits - 1)) as f64;
    assert_eq!((full as f32, zero as f32), (ADC_FULL_CODE, IMON_ZERO_CODE));
    // the reference's span at the ADC is vref / (R x gain) of current
    let span_ua = vref / (r_ohm * gain) * 1e6;
    assert!((span_ua - IMON_SPAN_UA as f64).abs() < 1e-3, "the parts give a {span_ua} µA span; IMON_SPAN_UA is {IMON_SPAN_UA}");
    let code_of = |ua: f64| zero + ua * 1e-6 * r_ohm * gain / vref * full;
    let trip = TRIP_CURRENT_UA as f64;
    // HTR the highest code below the trip, LTR the lowest above its mirror
    let (htr, ltr) = ((code_of(trip).ceil() - 1.0) as u16, (code_of(-trip).floor() + 1.0) as u16);
    let c = awd_codes();
    assert_eq!((c.current_high, c.current_low), (htr, ltr), "ADC1's HTR, LTR from the parts");
    // the charging current the docs allow on a fast slew (C at the 2/3 limit x 150 kV/s) flags neither way
    let slew_ua = 24.0;
    assert!(code_of(slew_ua) < htr as f64 && code_of(-slew_ua) > ltr as f64, "{} .. {}", code_of(-slew_ua), code_of(slew_ua));
    // the docs say what the code computes
    let flat = doc.split_whitespace().collect::<Vec<_>>().join(" ");
    for claim in [format!("ADC_HTR {}:", c.current_high), format!("ADC_LTR {}:", c.current_low), format!("60 V, ADC_HTR {})", c.volts_high)] {
        assert!(flat.contains(&claim), "docs/firmware.md should say {claim:?}");
    }
}

/// The trip's channel: the newest sample out of the window in the last two groups, at any
/// position of the DMA (wrapping too); else the largest current of the last group.
#[test]
fn the_trip_names_the_channel_out_of_its_window() {
    let c = awd_codes();
    for at in 0..BUF_WORDS {
        for ch in 0..HV_CHANNELS {
            for (bad_i, bad_v) in [(c.current_high + 1, 100), (c.current_low - 1, 100), (2048, c.volts_high + 1)] {
                let mut buf = [pair(2048, 1000); BUF_WORDS];
                // the newest group before `at` holding channel ch's word
                let mut w = (at + BUF_WORDS - 1) % BUF_WORDS;
                while w % HV_CHANNELS != ch {
                    w = (w + BUF_WORDS - 1) % BUF_WORDS;
                }
                buf[w] = pair(bad_i, bad_v);
                assert_eq!(trip_channel(at, |i| buf[i], &c) as usize, ch, "at {at} ch {ch}");
            }
        }
    }
    // nothing out of the window yet (the sample still in ADC_CDR): the largest current
    let mut buf = [pair(2048, 1000); BUF_WORDS];
    buf[BUF_WORDS - 2] = pair(3000, 1000);
    assert_eq!(trip_channel(0, |i| buf[i], &c), ((BUF_WORDS - 2) % 3) as u8);
}

/// A window's mean of a constant buffer is its code (no off-by-one in the wrap).
#[test]
fn a_constant_buffer_averages_to_its_codes_everywhere() {
    let mut buf = [0u32; BUF_WORDS];
    for (w, b) in buf.iter_mut().enumerate() {
        let k = w % 3;
        *b = pair(2000 + k as u16, 3000 + k as u16);
    }
    for at in 0..BUF_WORDS {
        let (v, i) = window_means(at, |w| buf[w]);
        assert_eq!(v, [3000.0, 3001.0, 3002.0], "at {at}");
        assert_eq!(i, [2000.0, 2001.0, 2002.0], "at {at}");
    }
}
