//! Time on the chip: SysTick as the 1 kHz control tick and the clock within it, and the
//! figures the `timing` console addition reports (docs/firmware.md "Real-time core").
//!
//! SysTick counts the core clock; QEMU's SysTick runs at the machine's core clock whatever the
//! RCC says (168 MHz netduinoplus2, 120 MHz netduino2), so a tick is `SYSTICK_PER_MS` counts in
//! every build. The figures are plain values: the tasks keep them in RTIC resources and the
//! report formats a copy. Not here: who measures what (src/main.rs).

use crate::num::Fixed;
use crate::rx::Record;
use core::fmt::Write;
#[cfg(not(m3))]
use cortex_m::peripheral::SCB;
use cortex_m::peripheral::{syst::SystClkSource, SYST};
use finger_protocol::field;

/// Core clock, MHz: 168 on the board and in QEMU netduinoplus2, 120 in QEMU netduino2 (M3).
#[cfg(not(m3))]
pub const CORE_MHZ: u32 = 168;
#[cfg(m3)]
pub const CORE_MHZ: u32 = 120;
/// SysTick counts per millisecond.
pub const SYSTICK_PER_MS: u32 = CORE_MHZ * 1000;

/// SysTick from the core clock, reloading every millisecond, its interrupt on.
pub fn start_systick(syst: &mut SYST) {
    syst.set_clock_source(SystClkSource::Core);
    syst.set_reload(SYSTICK_PER_MS - 1);
    syst.clear_current();
    syst.enable_interrupt();
    syst.enable_counter();
}

/// SysTick counts since its last reload.
pub fn systick_elapsed() -> u32 {
    (SYSTICK_PER_MS - 1).saturating_sub(SYST::get_current())
}

/// SysTick counts since the reload that began the running control tick, also past the next
/// reload (whose exception pends while the control task runs): a clock that does not run
/// backwards within a tick that overruns its millisecond once. Under the wall-clock emulator a
/// host stall can pass two reloads; spans then read short (`saturating_sub`: 0), never 2^32.
/// The Cortex-M3 image (its flash) reads [`systick_elapsed`]: a span across the reload, 0.
#[cfg(not(m3))]
pub fn tick_clock() -> u32 {
    loop {
        let before = SCB::is_pendst_pending();
        let c = systick_elapsed();
        if SCB::is_pendst_pending() == before {
            return if before { c + SYSTICK_PER_MS } else { c };
        }
    }
}

#[cfg(m3)]
pub use systick_elapsed as tick_clock;

/// What the control and console tasks measure, SysTick counts.
#[derive(Clone, Copy)]
pub struct Timing {
    /// Control-task entry after the SysTick reload (the tick's jitter), min and max.
    pub tick_latency: (u32, u32),
    /// Control-task run time, max.
    pub tick_run_max: u32,
    /// One channel's stack step in a control tick (goal, slew, guard, thickness, relaxation), max.
    pub tick_stack_max: u32,
    /// The read-back's work in a tick (estimate, checks, guard, loop), max; and its source's
    /// (the ADC's averages, or the emulator's plant), max.
    pub tick_sense_max: u32,
    pub tick_source_max: u32,
    /// Entry to entry of the control task, min and max.
    pub period: (u32, u32),
    /// Stop: from the console interrupt's entry to HV off, max; and how many.
    pub stop_max: u32,
    pub stops: u32,
    /// Control ticks counted.
    pub ticks: u32,
    /// The plant's trip latency, injection to the enable low, worst so far, µs (the emulator
    /// image: its faults come from its plant).
    pub trip_max_us: Option<u32>,
}

impl Timing {
    pub const fn new() -> Self {
        Timing {
            tick_latency: (u32::MAX, 0),
            tick_run_max: 0,
            tick_stack_max: 0,
            tick_sense_max: 0,
            tick_source_max: 0,
            period: (u32::MAX, 0),
            stop_max: 0,
            stops: 0,
            ticks: 0,
            trip_max_us: None,
        }
    }
}

impl Default for Timing {
    fn default() -> Self {
        Self::new()
    }
}

/// `v` into a (min, max) pair.
pub fn min_max(m: &mut (u32, u32), v: u32) {
    m.0 = m.0.min(v);
    m.1 = m.1.max(v);
}

/// Worst command durations by command word, SysTick counts (the command side's own).
pub const DURATION_SLOTS: usize = 12;

#[derive(Clone, Copy)]
pub struct Durations([([u8; 8], u32); DURATION_SLOTS]);

impl Durations {
    pub const fn new() -> Self {
        Durations([([0; 8], 0); DURATION_SLOTS])
    }
    /// The first word of a queued line (none for an error record); a word that is no command
    /// of this build's `help` is filed as `unknown`.
    pub fn word_of(rec: &Record) -> [u8; 8] {
        let mut w = [0u8; 8];
        if let Record::Line(l) = rec {
            let mut word = l.split(|&c| c == b' ' || c == b'\t').filter(|t| !t.is_empty());
            let Some(first) = word.next() else { return w };
            let first: &[u8] = if crate::app::is_command(first) { first } else { b"unknown" };
            for (i, &c) in first.iter().take(8).enumerate() {
                w[i] = c;
            }
        }
        w
    }
    pub fn record(&mut self, word: [u8; 8], counts: u32) {
        if word[0] == 0 {
            return;
        }
        for slot in self.0.iter_mut() {
            if slot.0 == word || slot.0[0] == 0 {
                slot.0 = word;
                slot.1 = slot.1.max(counts);
                return;
            }
        }
    }
}

impl Default for Durations {
    fn default() -> Self {
        Self::new()
    }
}

/// The `timing` reply: `tick_period_us=<min>,<max>` (control-task entry to entry),
/// `tick_latency_us=<min>,<max>` (control-task entry after the SysTick reload: the tick's
/// jitter), `tick_run_us=<max>`, `tick_stack_us=<max>`, `ticks=<n>`, `stop_us=<max>` (console
/// interrupt entry to HV off), `stops=<n>`, `trip_us=<max>` (a plant's fault, injection to the
/// enable low: the emulator image), `tick_sense_us=<max> tick_source_us=<max>` (a board with a
/// read-back: its work in a tick, and its source's: the ADC averages or the plant), `cmd_us=<word>:<max>,...` (the command side, line run,
/// replies queued).
pub fn write_timing(o: &mut dyn Write, t: &Timing, d: &Durations) {
    let us = |c: u32| Fixed(c as f32 / CORE_MHZ as f32, 2);
    let unset0 = |v: u32| if v == u32::MAX { 0 } else { v };
    let _ = w!(o; field::TICK_PERIOD_US.first(), us(unset0(t.period.0)), ",", us(t.period.1), field::TICK_LATENCY_US.after(), us(unset0(t.tick_latency.0)), ",", us(t.tick_latency.1), field::TICK_RUN_US.after(), us(t.tick_run_max), field::TICK_STACK_US.after(), Fixed(t.tick_stack_max as f32 / CORE_MHZ as f32, 3), field::TICKS.after(), t.ticks);
    let _ = w!(o; field::STOP_US.after(), us(t.stop_max), field::STOPS.after(), t.stops);
    if let Some(trip) = t.trip_max_us {
        let _ = w!(o; field::TRIP_US.after(), trip);
    }
    if t.tick_sense_max > 0 {
        let _ = w!(o; field::TICK_SENSE_US.after(), Fixed(t.tick_sense_max as f32 / CORE_MHZ as f32, 3), field::TICK_SOURCE_US.after(), Fixed(t.tick_source_max as f32 / CORE_MHZ as f32, 3));
    }
    let _ = w!(o; field::CMD_US.after());
    let mut first = true;
    for (word, c) in d.0.iter() {
        if word[0] == 0 {
            continue;
        }
        if !first {
            let _ = o.write_str(",");
        }
        first = false;
        let n = word.iter().position(|&b| b == 0).unwrap_or(8);
        let _ = w!(o; crate::console::printable(&word[..n]), ":", us(*c));
    }
}
