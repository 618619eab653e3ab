//! The analog watchdog's cut on the HV outputs (board build: `chip::hv_adc`'s trip handler
//! sets it, `chip::f405` wraps the outputs in it; host-tested in host-tests/tests/hv_cut.rs).
//!
//! One atomic holds the trip: set by the handler (which has already driven the enable low and
//! the duties to 0 by register stores), taken by the next control tick's read-back
//! ([`TripCell::take`]), which latches `breakdown` in the same tick. Until it is taken the cut
//! stands: [`CutEnable`] refuses to raise the enable and [`CutPwm`] holds every duty at 0,
//! whatever the core writes (a `stop`, `arm` and `volt` before the tick included). So the cut
//! ends only where the trip is consumed, never on a mere drop of the enable.

use core::convert::Infallible;
use core::sync::atomic::{AtomicU8, Ordering};

use embedded_hal::digital::{ErrorType, OutputPin};
use embedded_hal::pwm::SetDutyCycle;

/// The last trip's channel + 1 (0: none), from the trip handler to the tick.
pub struct TripCell(AtomicU8);

impl TripCell {
    pub const fn new() -> Self {
        TripCell(AtomicU8::new(0))
    }

    /// The trip handler: channel `ch` tripped (the enable and the duties already low).
    pub fn trip(&self, ch: u8) {
        self.0.store(ch.saturating_add(1), Ordering::Release);
    }

    /// A trip the tick has not yet taken: the cut stands.
    pub fn cut(&self) -> bool {
        self.0.load(Ordering::Acquire) != 0
    }

    /// The tick's read-back takes the trip (its channel), which ends the cut.
    pub fn take(&self) -> Option<u8> {
        match self.0.swap(0, Ordering::AcqRel) {
            0 => None,
            k => Some(k - 1),
        }
    }
}

impl Default for TripCell {
    fn default() -> Self {
        Self::new()
    }
}

/// An HV control PWM held at duty 0 while the cut stands.
pub struct CutPwm<P> {
    pwm: P,
    cell: &'static TripCell,
}

impl<P> CutPwm<P> {
    pub fn new(pwm: P, cell: &'static TripCell) -> Self {
        CutPwm { pwm, cell }
    }
    pub fn inner(&self) -> &P {
        &self.pwm
    }
    /// The PWM past the cut (the trip handler's own register stores, in a test).
    pub fn inner_mut(&mut self) -> &mut P {
        &mut self.pwm
    }
}

impl<P: SetDutyCycle> embedded_hal::pwm::ErrorType for CutPwm<P> {
    type Error = P::Error;
}

impl<P: SetDutyCycle> SetDutyCycle for CutPwm<P> {
    fn max_duty_cycle(&self) -> u16 {
        self.pwm.max_duty_cycle()
    }
    /// The duty, or 0 under the cut; stored, then the cut checked again: a trip between the
    /// check and the store (whose handler zeroed the register first) is zeroed here after it.
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), P::Error> {
        let d = if self.cell.cut() { 0 } else { duty };
        self.pwm.set_duty_cycle(d)?;
        if d != 0 && self.cell.cut() {
            self.pwm.set_duty_cycle(0)?;
        }
        Ok(())
    }
}

/// The HV enable, which does not rise while the cut stands (the core sees the trip at its
/// next tick and drops it itself).
pub struct CutEnable<P> {
    pin: P,
    cell: &'static TripCell,
}

impl<P> CutEnable<P> {
    pub fn new(pin: P, cell: &'static TripCell) -> Self {
        CutEnable { pin, cell }
    }
    pub fn inner(&self) -> &P {
        &self.pin
    }
    /// The pin past the cut (the trip handler's own register store, in a test).
    pub fn inner_mut(&mut self) -> &mut P {
        &mut self.pin
    }
}

impl<P: OutputPin<Error = Infallible>> ErrorType for CutEnable<P> {
    type Error = Infallible;
}

impl<P: OutputPin<Error = Infallible>> OutputPin for CutEnable<P> {
    /// Low; the cut stands until the tick takes the trip.
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.pin.set_low()
    }
    /// High unless the cut stands (then left low: `Ok`, the tick's `breakdown` follows).
    fn set_high(&mut self) -> Result<(), Infallible> {
        if self.cell.cut() {
            return self.pin.set_low();
        }
        self.pin.set_high()?;
        // a trip between the check and the store: its handler's BSRR store came first
        if self.cell.cut() {
            self.pin.set_low()?;
        }
        Ok(())
    }
}
