//! The STM32F405 board support (target only): the chip behind [`crate::Board`], shared by the
//! firmware image (src/main.rs: the tasks and their priorities, the reset and fault paths) and
//! the on-target tests (tests/on_target.rs).
//!
//! - [`f405`]: clocks, pins, the PWMs, the console USART's halves, the watchdog: `bring_up`.
//! - [`usart`]: the console's receive read and the transmit queue.
//! - [`time`]: SysTick as the control tick and the clock within it; the `timing` figures.
//! - [`mpu`]: the stack guard.
//! - [`flash`]: the settings store's flash (feature `settings`).
//! - [`hv_adc`]: the board build's HV read-back: ADCs, DMA, the analog watchdog (feature `hw`).
//!
//! Builds (Cargo features): `qemu` (QEMU netduinoplus2: HSI clock, no watchdog, defmt over
//! semihosting) or `hw` (the board: PLL from the crystal, IWDG, defmt over RTT); `cfg(m3)`,
//! set by build.rs for thumbv7m, is the Cortex-M3 emulator image (QEMU netduino2).
//! Not here: the application (the rest of this library), the tasks (src/main.rs).

pub mod f405;
#[cfg(feature = "settings")]
pub mod flash;
#[cfg(feature = "hw")]
pub mod hv_adc;
pub mod mpu;
pub mod time;
pub mod usart;

#[cfg(all(feature = "qemu", feature = "hw"))]
compile_error!("features `qemu` and `hw` are exclusive: build the board with --no-default-features --features hw");
#[cfg(not(any(feature = "qemu", feature = "hw")))]
compile_error!("choose a build: feature `qemu` (default) or `hw` (--no-default-features --features hw)");
#[cfg(all(m3, feature = "hw"))]
compile_error!("the Cortex-M3 image is an emulator image (QEMU netduino2): build it with --features m3");
