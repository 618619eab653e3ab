//! A simulated board: PWMs and the enable pin are plain values the host can inspect.
//! `finger-sim` and the host tests run the application against it.

use core::convert::Infallible;
use embedded_hal::digital::{ErrorType as PinErrorType, OutputPin};
use embedded_hal::pwm::{ErrorType as PwmErrorType, SetDutyCycle};

#[cfg(not(feature = "hw"))]
use crate::board::HvSense;
use crate::board::{Board, HV_CHANNELS};
#[cfg(not(feature = "hw"))]
use crate::plant::Plant;

/// A PWM output: the last duty written and how many writes.
#[derive(Clone, Copy, Debug, Default)]
pub struct SimPwm {
    pub duty: u16,
    pub max: u16,
    pub writes: u32,
}

impl PwmErrorType for SimPwm {
    type Error = Infallible;
}

impl SetDutyCycle for SimPwm {
    fn max_duty_cycle(&self) -> u16 {
        self.max
    }
    fn set_duty_cycle(&mut self, duty: u16) -> Result<(), Infallible> {
        self.duty = duty;
        self.writes += 1;
        Ok(())
    }
}

/// An output pin; `high_ever` records whether it was ever driven high.
#[derive(Clone, Copy, Debug, Default)]
pub struct SimPin {
    pub high: bool,
    pub high_ever: bool,
}

impl PinErrorType for SimPin {
    type Error = Infallible;
}

impl OutputPin for SimPin {
    fn set_low(&mut self) -> Result<(), Infallible> {
        self.high = false;
        Ok(())
    }
    fn set_high(&mut self) -> Result<(), Infallible> {
        self.high = true;
        self.high_ever = true;
        Ok(())
    }
}

/// The simulated board. Resolutions as on the STM32F405 at 168 MHz: servo TIM3 at 50 Hz,
/// HV TIM4 at 20 kHz (8400 counts).
#[derive(Clone, Debug)]
pub struct SimBoard {
    pub servo: SimPwm,
    pub hv: [SimPwm; HV_CHANNELS],
    pub enable: SimPin,
    pub watchdog_feeds: u64,
    /// The HV plant behind a read-back (None: no read-back, the HV runs open loop).
    #[cfg(not(feature = "hw"))]
    pub plant: Option<Plant>,
}

#[cfg(not(feature = "hw"))]
impl SimBoard {
    /// The board with the plant behind its read-back (finger-sim, the plant's tests).
    pub fn with_plant(plant: Plant) -> Self {
        SimBoard { plant: Some(plant), ..SimBoard::default() }
    }
}

impl Default for SimBoard {
    fn default() -> Self {
        // 0.5 us resolution: 40000 counts per 20 ms period.
        let servo = SimPwm { duty: 0, max: 40_000, writes: 0 };
        let hv = SimPwm { duty: 0, max: 8_400, writes: 0 };
        SimBoard {
            servo,
            hv: [hv; HV_CHANNELS],
            enable: SimPin::default(),
            watchdog_feeds: 0,
            #[cfg(not(feature = "hw"))]
            plant: None,
        }
    }
}

impl Board for SimBoard {
    type Servo = SimPwm;
    type Hv = SimPwm;
    type Enable = SimPin;
    fn servo(&mut self) -> &mut SimPwm {
        &mut self.servo
    }
    fn hv(&mut self, ch: usize) -> &mut SimPwm {
        &mut self.hv[ch]
    }
    fn hv_enable(&mut self) -> &mut SimPin {
        &mut self.enable
    }
    fn feed_watchdog(&mut self) {
        self.watchdog_feeds += 1;
    }
    fn name(&self) -> &'static str {
        "sim"
    }
    fn newline(&self) -> &'static str {
        "\n"
    }
    #[cfg(not(feature = "hw"))]
    fn hv_sense(&mut self) -> Option<HvSense> {
        let duty = [self.hv[0].duty, self.hv[1].duty, self.hv[2].duty];
        let (max, enable) = (self.hv[0].max, self.enable.high);
        self.plant.as_mut().map(|p| p.tick(duty, max, enable))
    }
    #[cfg(not(feature = "hw"))]
    fn plant(&mut self) -> Option<&mut Plant> {
        self.plant.as_mut()
    }
}

// ------------------------------------------------------------------------- virtual time

use crate::app::App;
use crate::rx::RxEvent;
use heapless::{Deque, String};

/// UART time of one byte at 115200 baud (10 bits), µs.
pub const BYTE_US: f64 = 10.0 / 115_200.0 * 1e6;

/// How long a command takes in virtual time, µs: from its line and the length of its reply.
pub type CostFn = fn(line: &[u8], reply_bytes: usize) -> u64;

/// The default cost: the compute of the command (instructions at 168 MHz, round upper
/// bounds of what QEMU measured before the real-time core; the firmware's `timing` reports
/// today's, docs/firmware.md "Figures") plus its reply at 115200 baud.
pub fn default_cost(line: &[u8], reply_bytes: usize) -> u64 {
    let word = line.split(|&c| c == b' ').find(|w| !w.is_empty()).unwrap_or(b"");
    let instr: u64 = match word {
        b"force" | b"volt" => 9_000_000,
        b"pose" => 10_000_000,
        b"contact" | b"limits" => 8_000_000,
        _ => 100_000,
    };
    instr / 168 + (reply_bytes as f64 * BYTE_US) as u64
}

/// A `&mut dyn Write` as a sized writer.
struct DynOut<'a>(&'a mut dyn core::fmt::Write);

impl core::fmt::Write for DynOut<'_> {
    fn write_str(&mut self, s: &str) -> core::fmt::Result {
        self.0.write_str(s)
    }
}

/// The command running in virtual time: its reply and setpoints wait for its end.
struct Running {
    end_us: u64,
    start_ms: u32,
    reply: String<32768>,
    setpoints: crate::control::Setpoints,
}

/// The application on the simulated board in virtual time: the same parts as on the chip
/// (RX with `stop` at once, the control core every 1 ms, the command side), with bytes that
/// arrive at 115200 baud and commands that take time ([`CostFn`]). During a command the
/// ticks run on the setpoints from before it, bytes arrive, a `stop` acts; the command's
/// setpoints are taken at its end (dropped if a stop came meanwhile) and its reply is written
/// then. No threads: [`VirtualSim::run_until`] steps the events in time order.
pub struct VirtualSim {
    pub app: App<SimBoard>,
    /// Virtual time, µs.
    pub t_us: u64,
    next_tick_us: u64,
    /// Bytes on the wire and their arrival times, µs.
    wire: Deque<(u64, u8), 16384>,
    wire_free_us: u64,
    running: Option<Running>,
    cost: CostFn,
}

impl VirtualSim {
    pub fn new(cost: CostFn) -> Self {
        VirtualSim { app: App::new(SimBoard::default()), t_us: 0, next_tick_us: 1000, wire: Deque::new(), wire_free_us: 0, running: None, cost }
    }

    /// Send bytes now (or after the bytes already on the wire), one per [`BYTE_US`]. False
    /// when the wire buffer is full (nothing sent).
    pub fn send(&mut self, bytes: &[u8]) -> bool {
        if self.wire.capacity() - self.wire.len() < bytes.len() {
            return false;
        }
        let mut t = (self.wire_free_us as f64).max(self.t_us as f64);
        for &b in bytes {
            t += BYTE_US;
            let _ = self.wire.push_back((t as u64, b));
        }
        self.wire_free_us = t as u64;
        true
    }

    /// Nothing on the wire, no command running, no `wait`.
    pub fn idle(&self) -> bool {
        self.wire.is_empty() && self.running.is_none() && !self.app.busy() && !self.app.rx.pending()
    }

    /// A command is running (its setpoints not yet taken).
    pub fn command_running(&self) -> bool {
        self.running.is_some()
    }

    /// Run to `until_us`: replies to `out`, `on_tick(app, t_us)` after every control tick.
    pub fn run_until(&mut self, until_us: u64, out: &mut dyn core::fmt::Write, on_tick: &mut dyn FnMut(&App<SimBoard>, u64)) {
        loop {
            let byte_t = self.wire.front().map(|&(t, _)| t).unwrap_or(u64::MAX);
            let end_t = self.running.as_ref().map(|r| r.end_us).unwrap_or(u64::MAX);
            let t = self.next_tick_us.min(byte_t).min(end_t);
            if t > until_us {
                self.t_us = until_us;
                return;
            }
            self.t_us = t;
            if t == end_t {
                self.finish_command(out);
            } else if t == byte_t {
                let (_, b) = self.wire.pop_front().unwrap_or((0, 0));
                if self.app.rx.push(b) == RxEvent::Stop {
                    self.app.ctl.stop();
                    let _ = w!(out; "ok stopped", self.app.cmds.newline());
                }
            } else {
                let checkin = match &self.running {
                    Some(r) => r.start_ms,
                    None => self.app.ctl.now_ms(),
                };
                self.app.ctl.tick(checkin);
                self.next_tick_us += 1000;
                on_tick(&self.app, t);
            }
            if self.running.is_none() {
                self.start_commands(out);
            }
        }
    }

    /// Run until idle (or `limit_us` more), as [`VirtualSim::run_until`].
    pub fn run_idle(&mut self, limit_us: u64, out: &mut dyn core::fmt::Write, on_tick: &mut dyn FnMut(&App<SimBoard>, u64)) {
        let end = self.t_us + limit_us;
        while !self.idle() && self.t_us < end {
            let next = (self.t_us + 1000).min(end);
            self.run_until(next, out, on_tick);
        }
    }

    fn finish_command(&mut self, out: &mut dyn core::fmt::Write) {
        if let Some(r) = self.running.take() {
            self.app.ctl.apply(&r.setpoints);
            let _ = out.write_str(&r.reply);
        }
    }

    /// The command side's turn at `t_us`: a `wait` may end, the next line starts.
    fn start_commands(&mut self, out: &mut dyn core::fmt::Write) {
        let app = &mut self.app;
        app.cmds.sync(&app.ctl.view());
        if app.cmds.busy() {
            let input = app.rx.take_input_seen();
            if !app.cmds.poll_wait(input, &mut DynOut(out)) {
                return;
            }
        }
        let Some(rec) = app.rx.pop() else { return };
        let mut line: heapless::Vec<u8, { crate::console::LINE_MAX }> = heapless::Vec::new();
        if let crate::rx::Record::Line(l) = &rec {
            let _ = line.extend_from_slice(l);
        }
        let start_ms = app.ctl.now_ms();
        let mut reply: String<32768> = String::new();
        app.cmds.run(rec, &mut reply);
        #[cfg(not(feature = "hw"))]
        if let Some(p) = app.cmds.take_plant() {
            app.ctl.plant_request(p);
        }
        #[cfg(not(m3))]
        if let Some(c) = app.cmds.take_sense_cal() {
            app.ctl.set_sense_cal(c.monitor, c.c0_pf);
        }
        if app.cmds.take_stop() {
            app.ctl.stop();
            app.cmds.sync(&app.ctl.view());
        }
        let setpoints = app.cmds.setpoints();
        let cost = (self.cost)(&line, reply.len());
        self.running = Some(Running { end_us: self.t_us + cost, start_ms, reply, setpoints });
        if cost == 0 {
            self.finish_command(out);
        }
    }
}
