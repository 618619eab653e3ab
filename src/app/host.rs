//! The host composition: [`App`], the whole application on one board without threads.
//!
//! What it is not: the chip's composition (src/main.rs runs the same parts as RTIC tasks).

use core::fmt::Write;

use finger_model::Finger;

use super::commands::Commands;
use super::params::{FwParams, CHANNELS};
use super::wire::wire;
use crate::board::Board;
#[cfg(feature = "hv-door")]
use crate::control::HvRefused;
use crate::control::{Control, Latched};
use crate::rx::{RxEvent, RxLines};

/// The whole application on one board, without threads: the RX part ([`RxLines`], `stop`
/// at once), the command side ([`Commands`]) and the control core ([`Control`]), run in turn.
/// The host's API (finger-sim, the host tests, the browser view): bytes in, replies out,
/// [`App::tick`] for each millisecond. `sim::VirtualSim` runs the same parts with commands
/// that take time.
pub struct App<B: Board> {
    pub(crate) cmds: Commands,
    pub(crate) ctl: Control<B>,
    pub(crate) rx: RxLines,
}

impl<B: Board> App<B> {
    /// Take the board: HV enable low, every HV duty 0, cable released. Default parameters.
    pub fn new(board: B) -> Self {
        let (cmds, ctl) = wire(board);
        App { cmds, ctl, rx: RxLines::new() }
    }

    pub fn board(&self) -> &B {
        self.ctl.board()
    }
    /// The board itself, past the control core (tests and the simulator only: feature `sim`).
    #[cfg(feature = "sim")]
    pub fn board_mut(&mut self) -> &mut B {
        self.ctl.board_mut()
    }
    pub fn commands(&self) -> &Commands {
        &self.cmds
    }
    pub fn control(&self) -> &Control<B> {
        &self.ctl
    }
    /// The control core itself (tests only: feature `hv-door`).
    #[cfg(feature = "hv-door")]
    pub fn control_mut(&mut self) -> &mut Control<B> {
        &mut self.ctl
    }
    pub fn finger(&self) -> &Finger<f32> {
        self.cmds.finger()
    }
    pub fn fw_params(&self) -> &FwParams {
        self.cmds.fw_params()
    }
    pub fn armed(&self) -> bool {
        self.cmds.armed()
    }
    pub fn hv_enabled(&self) -> bool {
        self.ctl.view().enable
    }
    /// Slewed HV values now, V.
    pub fn volts(&self) -> [f32; CHANNELS] {
        self.ctl.view().volts
    }
    pub fn targets(&self) -> [f32; CHANNELS] {
        self.cmds.targets()
    }
    pub fn vmax(&self) -> [f32; CHANNELS] {
        self.cmds.vmax()
    }
    pub fn duty_ceiling(&self) -> [u16; CHANNELS] {
        self.cmds.duty_ceiling()
    }
    pub fn duties(&self) -> [u16; CHANNELS] {
        self.ctl.view().duty
    }
    pub fn fault(&self) -> Latched {
        self.ctl.view().fault
    }
    /// A `wait` is running: call `tick` until it ends (input meanwhile ends it early).
    pub fn busy(&self) -> bool {
        self.cmds.busy()
    }
    pub fn now_ms(&self) -> u32 {
        self.ctl.now_ms()
    }
    pub fn fmax_evaluations(&self) -> u32 {
        self.cmds.fmax_evaluations()
    }

    /// The single HV writer called directly: tests only (feature `hv-door`), for its refusals.
    #[cfg(feature = "hv-door")]
    pub fn write_hv_duty(&mut self, ch: usize, duty: u16) -> Result<(), HvRefused> {
        let r = self.ctl.write_hv_duty(ch, duty);
        self.cmds.sync(&self.ctl.view());
        r
    }

    /// Emergency stop: HV off at once, cable released, disarmed. Clears a latched fault.
    pub fn emergency_stop(&mut self) {
        self.ctl.stop();
        self.cmds.sync(&self.ctl.view());
    }

    /// `dt_ms` control ticks, then the command side's turn (a `wait` may end).
    pub fn tick<W: Write>(&mut self, dt_ms: u32, out: &mut W) {
        for _ in 0..dt_ms {
            // the command side is idle between calls: it checks in every tick
            let now = self.ctl.now_ms();
            self.ctl.tick(now);
        }
        self.run_commands(out);
    }

    /// Feed received bytes; replies go to `out`.
    pub fn input<W: Write>(&mut self, bytes: &[u8], out: &mut W) {
        for &b in bytes {
            self.input_byte(b, out);
        }
    }

    /// One received byte: the RX part (a `stop` acts here), then the command side runs
    /// what is queued (nothing while a `wait` runs; input ends a `wait` early).
    pub fn input_byte<W: Write>(&mut self, b: u8, out: &mut W) {
        self.receive(b, out);
        self.run_commands(out);
    }

    /// The UART lost bytes here (an overrun): the line being received is discarded at its
    /// end and answered `err overrun` (QEMU's UART never overruns: the host tests use this).
    pub fn input_overrun(&mut self) {
        self.rx.overrun();
    }

    /// The RX interrupt's part of a byte (a `stop` acts here and drops the lines queued ahead
    /// of it); the line queues until the command side's turn ([`App::run_commands`]), as on a
    /// board whose command side is busy while bytes arrive.
    pub fn receive<W: Write>(&mut self, b: u8, out: &mut W) {
        if self.rx.push(b) == RxEvent::Stop {
            self.ctl.stop();
            let _ = w!(out; "ok stopped", self.cmds.nl);
        }
    }

    /// The command side: every queued line in turn, each one's setpoints to the core.
    pub fn run_commands<W: Write>(&mut self, out: &mut W) {
        loop {
            self.cmds.sync(&self.ctl.view());
            if self.cmds.busy() {
                let input = self.rx.take_input_seen();
                if !self.cmds.poll_wait(input, out) {
                    return;
                }
            }
            let Some(rec) = self.rx.pop() else { return };
            self.cmds.run(rec, out);
            self.hand_over();
        }
    }

    /// Run one line (without terminator) on the command side; its setpoints to the core.
    pub fn execute<W: Write>(&mut self, line: &[u8], out: &mut W) {
        self.cmds.sync(&self.ctl.view());
        self.cmds.execute(line, out);
        self.hand_over();
    }

    /// After a line: a `stop` it executed stops the core; its setpoints to the core.
    fn hand_over(&mut self) {
        #[cfg(not(feature = "hw"))]
        if let Some(p) = self.cmds.take_plant() {
            self.ctl.plant_request(p);
        }
        #[cfg(not(m3))]
        if let Some(c) = self.cmds.take_sense_cal() {
            self.ctl.set_sense_cal(c.monitor, c.c0_pf);
        }
        if self.cmds.take_stop() {
            self.ctl.stop();
            self.cmds.sync(&self.ctl.view());
        }
        let sp = self.cmds.setpoints();
        self.ctl.apply(&sp);
    }
}
