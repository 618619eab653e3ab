//! The board's HV read-back (board build, feature `hw`; never in an emulator image): TIM2's
//! update at 10 kHz triggers ADC1 (the three return currents) and ADC2 (the three voltage
//! monitors) in dual regular simultaneous mode, DMA2 stream 0 moves each pair (ADC_CDR) into a
//! circular buffer of two ticks' halves, and the control tick averages the last tick's
//! samples ([`HvAdc::sense`]). The analog watchdogs (ADC1 on the currents both ways, ADC2 on
//! the voltages past the hard limit) interrupt at the top priority ([`on_watchdog`]: the
//! `hv_trip` task of src/main.rs), which drops the HV enable and zeroes the duties by
//! register stores and leaves the channel for the tick.
//!
//! Registers by RM0090's names. The arithmetic (layout, bookkeeping, thresholds, the trip's
//! channel) is `crate::sampling`, host-tested; this is the part no test here runs (QEMU does
//! not model the F405's ADC: docs/firmware.md "HV read-back").
//!
//! Pins (docs/firmware.md): PC0..PC2 ADC2 IN10..12 (voltage monitors 1..3), PC3 ADC1 IN13,
//! PA1 ADC1 IN1, PA2 ADC1 IN2 (return currents 1..3).

use stm32f4xx_hal::{pac, rcc::Enable, rcc::Rcc};

use crate::board::HvSense;
use crate::cut::TripCell;
use crate::sampling::{awd_codes, trip_channel, writing_at, HalfFlags, Halves, BUF_WORDS};

/// The DMA's buffer (SRAM1, which DMA2 reaches): written by the DMA only, read by volatile loads.
#[repr(C, align(4))]
struct Buf([u32; BUF_WORDS]);
static mut BUF: Buf = Buf([0; BUF_WORDS]);

/// The last trip, from the interrupt to the tick; while the tick has not taken it, the cut
/// stands on the HV outputs (`crate::cut`, `f405`'s pins).
pub static TRIP: TripCell = TripCell::new();

/// The buffer's word `i` (volatile: the DMA writes it).
fn word(i: usize) -> u32 {
    // SAFETY: an aligned in-bounds read of the DMA buffer; the DMA is its only writer.
    unsafe { core::ptr::read_volatile(core::ptr::addr_of!(BUF.0[i % BUF_WORDS])) }
}

// RM0090 bit positions used below
const CR1_AWDIE: u32 = 1 << 6;
const CR1_SCAN: u32 = 1 << 8;
const CR1_AWDEN: u32 = 1 << 23;
const CR2_ADON: u32 = 1 << 0;
const CR2_EXTSEL_TIM2_TRGO: u32 = 0b0110 << 24;
const CR2_EXTEN_RISING: u32 = 0b01 << 28;
const SR_AWD: u32 = 1 << 0;
/// TIMx_EGR.UG: an update event (the preloaded registers into the active ones).
const TIM_EGR_UG: u32 = 1 << 0;
/// ADC_CCR: MULTI = 00110 (dual regular simultaneous), DMA mode 2 (DMA = 10), DDS = 1,
/// ADCPRE = 01 (PCLK2 / 4 = 21 MHz).
const CCR_DUAL_REGULAR: u32 = 0b00110;
const CCR_DDS: u32 = 1 << 13;
const CCR_DMA_MODE2: u32 = 0b10 << 14;
const CCR_ADCPRE_DIV4: u32 = 0b01 << 16;
/// DMA_SxCR: channel 0, priority very high, 32-bit memory and peripheral, memory increment,
/// circular, peripheral to memory, EN.
const DMA_CR: u32 = (0b11 << 16) | (0b10 << 13) | (0b10 << 11) | (1 << 10) | (1 << 8);
const DMA_EN: u32 = 1 << 0;
/// LISR / LIFCR, stream 0: HTIF0 (bit 4), TCIF0 (bit 5).
const HTIF0: u32 = 1 << 4;
const TCIF0: u32 = 1 << 5;
/// Sample time of every channel: 144 cycles (SMPx = 110): 156 ADC clocks a conversion, 7.4 µs
/// at 21 MHz; three in scan, 22 µs of the trigger's 100 µs.
const SMP_144: u32 = 0b110;
/// TIM2 (APB1 timer clock 84 MHz): 84 MHz / (PSC + 1) / (ARR + 1) = 10 kHz; TRGO on update.
const TIM2_PSC: u32 = 0;
const TIM2_ARR: u32 = 8_400 - 1;

/// The read-back's state in the board: the bookkeeping of the halves.
pub struct HvAdc {
    halves: Halves,
}

/// The sampling chain brought up and running: RCC clocks, the analog pins (the caller puts
/// them in analog mode), ADC1/ADC2 dual with their watchdogs and the interrupt armed (its
/// priority is RTIC's, src/main.rs), DMA2 stream 0 circular, TIM2 at 10 kHz.
pub fn start(rcc: &mut Rcc, adc1: pac::ADC1, adc2: pac::ADC2, common: pac::ADC_COMMON, dma2: pac::DMA2, tim2: pac::TIM2) -> HvAdc {
    pac::ADC1::enable(rcc);
    pac::ADC2::enable(rcc);
    pac::DMA2::enable(rcc);
    pac::TIM2::enable(rcc);
    let codes = awd_codes();
    // SAFETY (every `bits` below): whole-register values built from RM0090's fields above.
    unsafe {
        // TIM2 first: UG loads PSC and ARR while CR2.MMS is still 000 (reset), in which UG
        // itself is TRGO: that pulse comes before any ADC takes the trigger. Then the update
        // event as TRGO (MMS = 010).
        tim2.psc().write(|w| w.bits(TIM2_PSC));
        tim2.arr().write(|w| w.bits(TIM2_ARR));
        tim2.egr().write(|w| w.bits(TIM_EGR_UG));
        tim2.cr2().write(|w| w.bits(0b010 << 4));
        common.ccr().write(|w| w.bits(CCR_DUAL_REGULAR | CCR_DDS | CCR_DMA_MODE2 | CCR_ADCPRE_DIV4));
        // DMA2 stream 0 (channel 0: ADC1, which carries the pairs in dual mode)
        let st = dma2.st(0);
        st.cr().write(|w| w.bits(0));
        while st.cr().read().en().bit_is_set() {}
        dma2.lifcr().write(|w| w.bits(0x3D));
        st.par().write(|w| w.bits(common.cdr().as_ptr() as u32));
        st.m0ar().write(|w| w.bits(core::ptr::addr_of!(BUF) as u32));
        st.ndtr().write(|w| w.bits(BUF_WORDS as u32));
        st.fcr().write(|w| w.bits(0)); // direct mode
        st.cr().write(|w| w.bits(DMA_CR));
        st.cr().modify(|r, w| w.bits(r.bits() | DMA_EN));

        // the sequences: three conversions each (SQR1.L = 2), channel k of the board at rank k + 1
        let smp_lo = (SMP_144 << 3) | (SMP_144 << 6); // SMPR2: IN1, IN2
        let smp_hi = SMP_144 | (SMP_144 << 3) | (SMP_144 << 6) | (SMP_144 << 9); // SMPR1: IN10..IN13
        for (adc, seq, awd) in [(&*adc1, [13u32, 1, 2], (codes.current_high, codes.current_low)), (&*adc2, [10u32, 11, 12], (codes.volts_high, 0))] {
            adc.smpr1().write(|w| w.bits(smp_hi));
            adc.smpr2().write(|w| w.bits(smp_lo));
            adc.sqr1().write(|w| w.bits(2 << 20));
            adc.sqr3().write(|w| w.bits(seq[0] | (seq[1] << 5) | (seq[2] << 10)));
            adc.htr().write(|w| w.bits(awd.0 as u32));
            adc.ltr().write(|w| w.bits(awd.1 as u32));
            // the watchdog on every regular channel (AWDSGL = 0), its interrupt
            adc.cr1().write(|w| w.bits(CR1_SCAN | CR1_AWDEN | CR1_AWDIE));
            adc.sr().write(|w| w.bits(0));
        }
        // the master (ADC1) takes the trigger; the slave follows it in dual mode
        adc1.cr2().write(|w| w.bits(CR2_ADON | CR2_EXTSEL_TIM2_TRGO | CR2_EXTEN_RISING));
        adc2.cr2().write(|w| w.bits(CR2_ADON));

        // TIM2 runs: its first update (TRGO) is one period (100 µs) after CEN, well past
        // the ADCs' power-up after ADON (t_STAB, 3 µs)
        tim2.cr1().write(|w| w.bits(1));
    }
    HvAdc { halves: Halves::new() }
}

impl HvAdc {
    /// The tick's read-back: the last tick's samples averaged, the halves seen since the
    /// last tick (cleared as seen), the watchdog's trip since then.
    pub fn sense(&mut self) -> HvSense {
        // SAFETY: reads of DMA2's stream 0 registers and a write of its own clear flags.
        let dma2 = unsafe { &*pac::DMA2::ptr() };
        let at = writing_at(dma2.st(0).ndtr().read().bits());
        let seen = dma2.lisr().read().bits() & (HTIF0 | TCIF0);
        // SAFETY: LIFCR clears exactly the flags read (one set after the read waits for the next tick).
        unsafe { dma2.lifcr().write(|w| w.bits(seen)) };
        let flags = HalfFlags { half: seen & HTIF0 != 0, full: seen & TCIF0 != 0 };
        // the trip taken here ends the cut: this tick latches `breakdown` from it
        self.halves.sense(flags, at, word, TRIP.take())
    }

    /// The bookkeeping so far (ticks, stale ticks, halves no tick read).
    pub fn halves(&self) -> Halves {
        self.halves
    }
}

/// GPIOB ODR bit 12: the HV enable is high.
fn enable_high() -> bool {
    // SAFETY: a read of GPIOB's output data register.
    unsafe { (*pac::GPIOB::ptr()).odr().read().bits() & (1 << 12) != 0 }
}

/// The analog watchdogs' interrupt (ADC, shared by ADC1 and ADC2), the top priority: with
/// the enable high, the HV enable low (GPIOB BSRR BR12) and TIM4 CCR1..3 = 0 first, then the
/// channel left for the tick; the flags cleared. With the enable already low there is nothing
/// to cut (a disarm's discharge), and no trip.
pub fn on_watchdog() {
    // SAFETY: register stores that only drive the HV outputs low, and reads and clears of
    // the ADCs' status flags (rc_w0: writing 0 clears, 1 leaves).
    unsafe {
        let adc1 = &*pac::ADC1::ptr();
        let adc2 = &*pac::ADC2::ptr();
        let flagged = (adc1.sr().read().bits() | adc2.sr().read().bits()) & SR_AWD != 0;
        if flagged && enable_high() {
            (*pac::GPIOB::ptr()).bsrr().write(|w| w.bits(1 << (12 + 16)));
            let tim4 = &*pac::TIM4::ptr();
            for k in 0..3 {
                tim4.ccr(k).write(|w| w.bits(0));
            }
            // the compare registers are preloaded (OCxPE): an update event moves the zeros
            // into the active registers now, not at the period's end (up to 50 µs)
            tim4.egr().write(|w| w.bits(TIM_EGR_UG));
            let at = writing_at((*pac::DMA2::ptr()).st(0).ndtr().read().bits());
            TRIP.trip(trip_channel(at, word, &awd_codes()));
        }
        adc1.sr().write(|w| w.bits(!SR_AWD & 0x3F));
        adc2.sr().write(|w| w.bits(!SR_AWD & 0x3F));
    }
}
