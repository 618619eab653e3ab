//! The driver-board application: serial console, setpoints, slew, safety and model calls.
//!
//! The application holds no chip code: it is generic over embedded-hal 1.0 traits
//! (`SetDutyCycle` for the servo PWM and the three HV control PWMs, `OutputPin` for the HV
//! enable) gathered by the small [`Board`] trait; `chip` (target only) implements it for the
//! STM32F405, [`sim::SimBoard`] for the host (`finger-sim`, the host tests).
//!
//! - [`console`]: line assembly (CR/LF/CRLF, bounded buffer, overlong lines), tokens, strict
//!   number parsing.
//! - [`app`]: the commands of docs/console.md, the HV ceilings, the model calls; [`App`], the
//!   whole application on one board for the host.
//! - [`control`]: the control core, the one owner of the outputs: the single HV-duty writer,
//!   the slew, the servo, the stop, the watchdog feed.
//! - [`rx`]: console input at interrupt level: lines, `stop` at once, a bounded ring of lines.
//! - [`board`]: the board trait; `chip` (target only): the STM32F405's board support.
//! - [`sim`]: a simulated board (records every output; with [`plant`] behind its read-back).
//! - [`plant`]: the simulated HV plant (modules, divider, stacks, faults, ADC), never in the
//!   board build.
//! - [`cut`]: the analog watchdog's cut on the board build's HV outputs (host-tested).
//! - [`sampling`]: the board's HV read-back sampling arithmetic (DMA halves, means, the
//!   analog watchdog's codes); host and board build only.
//! - [`out`], [`num`]: console text and numbers without core's formatting machinery.
//! - [`flash_ctl`]: the F405 flash controller's sequences over a register trait (host-tested;
//!   the board build's settings flash).
//! - [`settings`], [`flash_ram`]: the stored settings' record and store, and the emulator's
//!   RAM flash (feature `settings`).
#![no_std]

#[macro_use]
pub mod out;
pub mod app;
pub mod board;
#[cfg(target_os = "none")]
pub mod chip;
pub mod console;
pub mod control;
pub mod cut;
#[cfg(any(feature = "hw", not(target_os = "none")))]
pub mod flash_ctl;
#[cfg(feature = "settings")]
pub mod flash_ram;
pub mod num;
#[cfg(not(feature = "hw"))]
pub mod plant;
pub mod rx;
#[cfg(any(feature = "hw", m3, not(target_os = "none")))]
pub mod sampling;
#[cfg(feature = "settings")]
pub mod settings;
pub mod sim;

pub use app::{wire, App, Commands, FwParams, CHANNELS};
pub use board::Board;

/// Firmware name, as `version` reports it.
pub const NAME: &str = "finger-fw";
/// Firmware version (the package version).
pub const VERSION: &str = env!("CARGO_PKG_VERSION");
