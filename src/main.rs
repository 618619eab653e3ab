//! The chip part: STM32F405 (thumbv7em-none-eabihf). Clocks, pins, PWMs, the UART console,
//! SysTick time, the watchdog, the panic and HardFault handlers. The application is in lib.rs.
//!
//! Pin map (docs/firmware.md):
//! - USART1 TX PA9, RX PA10: console, 115200 8N1
//! - TIM3 CH1 PA6: servo PWM, 50 Hz, 1.0..2.0 ms
//! - TIM4 CH1..CH3 PB6, PB7, PB8: HV modules' control inputs (PWM 20 kHz, RC-filtered to 0..5 V)
//! - PB12: HV enable (interlock), push-pull, low unless armed (external pull-down on the board)
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
mod chip;

/// On the host the firmware binary is empty: the application runs in tools/finger-sim.
#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("finger-fw is firmware for thumbv7em-none-eabihf; on the host use tools/finger-sim");
}
