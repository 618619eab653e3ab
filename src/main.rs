//! The firmware image: the RTIC 2 real-time core over the chip's board support
//! (`finger_fw::chip`), and what only the image has: the HV-off reset and fault paths
//! (image/fault.rs), its `memcpy` (image/mem.rs), the `crash` test command (image/fault_inject.rs).
//! The tasks, their priorities and resources are stated once, in [`app`] below.
//! The application is the library (src/lib.rs); on the host this binary is empty.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

#[cfg(target_os = "none")]
#[path = "image/fault.rs"]
mod fault;
#[cfg(all(target_os = "none", feature = "fault-inject"))]
#[path = "image/fault_inject.rs"]
mod fault_inject;
#[cfg(target_os = "none")]
#[path = "image/mem.rs"]
mod mem;

#[cfg(all(target_os = "none", feature = "log", feature = "hw"))]
use defmt_rtt as _;
#[cfg(all(target_os = "none", feature = "log", feature = "qemu"))]
use defmt_semihosting as _;

/// On the host the firmware binary is empty: the application runs in tools/finger-sim.
#[cfg(not(target_os = "none"))]
fn main() {
    eprintln!("finger-fw is firmware for thumbv7em-none-eabihf; on the host use tools/finger-sim");
}

/// Setpoints down to the control core, its view and the command side's check-in across.
#[cfg(target_os = "none")]
pub struct Mailbox {
    setpoints: Option<finger_fw::control::Setpoints>,
    /// A `stop` executed as a line on the command side.
    stop: bool,
    view: finger_fw::control::View,
    /// The command side's last check-in, control ms (the watchdog feeds only after a recent one).
    checkin_ms: u32,
    /// A `plant ...` line's change to the emulator's plant.
    #[cfg(feature = "qemu")]
    plant: Option<finger_fw::control::PlantRequest>,
    /// A `cal vmon|c0` line's calibration for the read-back.
    #[cfg(not(m3))]
    sense_cal: Option<finger_fw::app::hv_cal::SenseCal>,
}

/// The real-time core. Priorities and interrupts, the one place they are set:
///
/// | prio | task | binds | does |
/// | --- | --- | --- | --- |
/// | 4 | `hv_trip` (board build) | ADC (ADC1/ADC2 analog watchdogs) | the HV enable low and the duties 0 by register stores, the channel left for the next tick (`finger_fw::chip::hv_adc`); no resources, so no lock raises to it |
/// | 3 | `control` | SysTick, 1 kHz | the control core (`finger_fw::control`): takes the setpoints, slew, the HV duties (single writer), servo, stop requests, watchdog feed |
/// | 2 | `console` | USART1 (RXNE, TXE) | each received byte into `finger_fw::rx` (a `stop` line stops the control core here, at once), the transmit queue out |
/// | 0 | `idle` | - | the command side (`finger_fw::Commands`): lines, model solves, `wait`, replies into the transmit queue |
///
/// Resources: `ctl` (control, console: the console's use is one `stop`), `mailbox` (control,
/// console after a stop, idle), `timing` (control, console, idle: a copy for `timing`),
/// `tx` (console, idle), `rx` (console, idle); the console's receive half and the command
/// side's durations are local. Every lock below the control task's priority holds a copy, a
/// stop or a line's queueing, never a formatting or a model solve.
#[cfg(target_os = "none")]
#[rtic::app(device = stm32f4xx_hal::pac, peripherals = true)]
mod app {
    use finger_fw::app::TimingReport;
    use finger_fw::chip::{f405, f405::F405Board, mpu, time, time::Durations, time::Timing, usart, usart::TxQueue};
    use finger_fw::control::Control;
    use finger_fw::rx::{RxEvent, RxLines};
    use finger_fw::Commands;
    use rtic::Mutex;

    #[shared]
    struct Shared {
        ctl: Control<F405Board>,
        mailbox: super::Mailbox,
        timing: Timing,
        rx: RxLines,
        tx: TxQueue,
    }

    #[local]
    struct Local {
        cmds: Commands,
        usart_rx: f405::ConsoleRx,
    }

    #[init]
    fn init(cx: init::Context) -> (Shared, Local) {
        // the HV pins are low since __pre_init (image/fault.rs), and again right after
        // bring_up's GPIOB split (which resets the port) until their set-up
        let mut cp = cx.core;
        let chip = f405::bring_up(cx.device);
        #[allow(unused_mut)] // mutated by the settings' boot only
        let (mut cmds, mut ctl) = finger_fw::wire(chip.board);
        // the stored settings, before the control tick starts
        #[cfg(feature = "settings")]
        let boot = finger_fw::chip::flash::store(chip.flash).map(|s| finger_fw::app::config::boot(&mut cmds, &mut ctl, s));
        // the watchdog from here: the store's read and repair above (erases, with no tick
        // to feed it) ran before it
        #[cfg(feature = "hw")]
        finger_fw::chip::f405::start_watchdog();
        if cfg!(feature = "qemu") && chip.real_chip {
            // the emulator image has no watchdog: it never arms a real board
            ctl.lock_out(finger_fw::control::Fault::EmulatorOnChip);
        }
        let view = ctl.view();

        let guard = mpu::stack_guard(&mut cp.MPU);
        time::start_systick(&mut cp.SYST);

        #[cfg(feature = "log")]
        defmt::info!("finger-fw {=str} up, board {=str}, stack guard at {=u32:#x}", finger_fw::VERSION, finger_fw::Board::name(ctl.board()), guard);
        let _ = guard;

        let mut tx = TxQueue::new(chip.tx);
        // Boot banner: not a reply; tells a client that input is now received (QEMU drops
        // bytes sent before the USART is enabled, a real UART too).
        tx.push_all(b"# finger-fw ");
        tx.push_all(finger_fw::VERSION.as_bytes());
        #[cfg(feature = "settings")]
        if let Some(b) = boot {
            let mut note: heapless::String<80> = heapless::String::new();
            let _ = finger_fw::w!(&mut note; " ", b);
            tx.push_all(note.as_bytes());
        }
        tx.push_all(b" ready\r\n");

        let mailbox = super::Mailbox {
            setpoints: None,
            stop: false,
            view,
            checkin_ms: 0,
            #[cfg(feature = "qemu")]
            plant: None,
            #[cfg(not(m3))]
            sense_cal: None,
        };
        (Shared { ctl, mailbox, timing: Timing::new(), rx: RxLines::new(), tx }, Local { cmds, usart_rx: chip.rx })
    }

    /// The control task: every 1 ms, at the highest priority (no lock waits here).
    #[task(binds = SysTick, priority = 3, shared = [ctl, mailbox, timing], local = [last_entry: u64 = 0])]
    fn control(cx: control::Context) {
        let entry = time::systick_elapsed();
        (cx.shared.ctl, cx.shared.mailbox, cx.shared.timing).lock(|ctl, mb, tm| {
            time::min_max(&mut tm.tick_latency, entry);
            let at = (mb.view.now_ms as u64 + 1) * time::SYSTICK_PER_MS as u64 + entry as u64;
            if *cx.local.last_entry > 0 {
                time::min_max(&mut tm.period, (at - *cx.local.last_entry) as u32);
            }
            *cx.local.last_entry = at;
            if core::mem::take(&mut mb.stop) {
                ctl.stop();
            }
            #[cfg(feature = "qemu")]
            if let Some(p) = mb.plant.take() {
                ctl.plant_request(p);
            }
            #[cfg(not(m3))]
            if let Some(c) = mb.sense_cal.take() {
                ctl.set_sense_cal(c.monitor, c.c0_pf);
            }
            if let Some(sp) = mb.setpoints.take() {
                ctl.apply(&sp);
            }
            let cost = ctl.tick_timed(mb.checkin_ms, time::tick_clock);
            tm.tick_stack_max = tm.tick_stack_max.max(cost.stack_step);
            tm.tick_sense_max = tm.tick_sense_max.max(cost.read_back);
            tm.tick_source_max = tm.tick_source_max.max(cost.sense_source);
            mb.view = ctl.view();
            tm.trip_max_us = mb.view.trip_max_us;
            #[cfg(feature = "qemu")]
            {
                // tick marker for the register trace (TIM4 CCR4: channel 4 is not an output)
                // SAFETY: a write of TIM4's fourth compare register, which no pin uses.
                unsafe { (*stm32f4xx_hal::pac::TIM4::ptr()).ccr(3).write(|w| w.bits(mb.view.now_ms & 0xFFFF)) };
                rtic::pend(stm32f4xx_hal::pac::Interrupt::USART1); // transmit (chip::usart)
            }
            tm.ticks += 1;
            tm.tick_run_max = tm.tick_run_max.max(time::tick_clock().saturating_sub(entry));
        });
    }

    /// The analog watchdogs (board build): above the control task, sharing nothing.
    #[cfg(feature = "hw")]
    #[task(binds = ADC, priority = 4)]
    fn hv_trip(_cx: hv_trip::Context) {
        finger_fw::chip::hv_adc::on_watchdog();
    }

    /// USART1: received bytes into the line ring (`stop` acts here), the transmit queue out.
    #[task(binds = USART1, priority = 2, shared = [ctl, mailbox, timing, rx, tx], local = [usart_rx])]
    fn console(cx: console::Context) {
        let t0 = time::systick_elapsed();
        let (ctl, mailbox, mut timing, mut rx, mut tx) = (cx.shared.ctl, cx.shared.mailbox, cx.shared.timing, cx.shared.rx, cx.shared.tx);
        if let Some((b, overrun)) = usart::receive(cx.local.usart_rx) {
            let ev = rx.lock(|r| {
                let ev = r.push(b);
                if overrun {
                    r.overrun(); // bytes after b were lost
                }
                ev
            });
            if ev == RxEvent::Stop {
                // HV off now; the command side sees the stop in the view before its next line
                (ctl, mailbox).lock(|c, m| {
                    c.stop();
                    m.view = c.view();
                });
                let t1 = time::systick_elapsed();
                timing.lock(|t| {
                    t.stop_max = t.stop_max.max(t1.wrapping_sub(t0) % time::SYSTICK_PER_MS);
                    t.stops += 1;
                });
                tx.lock(|t| t.push_stop_reply());
            }
        }
        tx.lock(|t| t.send());
    }

    /// The command side, at the lowest priority: lines, model solves, `wait`, replies.
    #[idle(shared = [mailbox, timing, rx, tx], local = [cmds, durations: Durations = Durations::new()])]
    fn idle(cx: idle::Context) -> ! {
        let (cmds, durations) = (cx.local.cmds, cx.local.durations);
        let (mailbox, timing, mut rx, tx) = (cx.shared.mailbox, cx.shared.timing, cx.shared.rx, cx.shared.tx);
        let mut out = TxOut { tx, mailbox, line: heapless::Vec::new() };
        let mut report = Report { timing, durations };
        loop {
            let view = out.check_in();
            cmds.sync(&view);
            if cmds.busy() {
                let input = rx.lock(|r| r.take_input_seen());
                if !cmds.poll_wait(input, &mut out) {
                    cortex_m::asm::wfi();
                    continue;
                }
            }
            let Some(rec) = rx.lock(|r| r.pop()) else {
                cortex_m::asm::wfi();
                continue;
            };
            let word = Durations::word_of(&rec);
            #[cfg(feature = "fault-inject")]
            crate::fault_inject::run(&rec);
            let t0 = out.now_counts();
            cmds.run_reporting(rec, &mut out, Some(&mut report));
            let t1 = out.now_counts();
            report.durations.record(word, (t1 - t0) as u32);
            #[cfg(not(m3))]
            if cmds.take_reset() {
                out.reboot();
            }
            let stop = cmds.take_stop();
            let sp = cmds.setpoints();
            #[cfg(feature = "qemu")]
            let plant = cmds.take_plant();
            #[cfg(not(m3))]
            let sense_cal = cmds.take_sense_cal();
            out.mailbox.lock(|m| {
                m.setpoints = Some(sp);
                m.stop |= stop;
                #[cfg(feature = "qemu")]
                {
                    m.plant = plant;
                }
                #[cfg(not(m3))]
                if sense_cal.is_some() {
                    m.sense_cal = sense_cal;
                }
            });
            // the next line sees this one's effect: the core takes the setpoints at its next
            // tick (or drops them after a stop)
            loop {
                let v = out.check_in();
                if v.seq == sp.seq || v.epoch != sp.epoch || stop {
                    break;
                }
                cortex_m::asm::wfi();
            }
        }
    }

    /// `timing`: the tasks' figures copied under their lock, formatted outside it.
    struct Report<T: Mutex<T = Timing>> {
        timing: T,
        durations: &'static mut Durations,
    }

    impl<T: Mutex<T = Timing>> TimingReport for Report<T> {
        fn write_timing(&mut self, out: &mut dyn core::fmt::Write) {
            let t = self.timing.lock(|t| *t);
            time::write_timing(out, &t, self.durations);
        }
    }

    /// Replies into the transmit queue, a whole line at a time (the command side waits for
    /// room, checking in meanwhile: a slow console is not a stuck one).
    struct TxOut<Q: Mutex<T = TxQueue>, M: Mutex<T = super::Mailbox>> {
        tx: Q,
        mailbox: M,
        line: heapless::Vec<u8, 512>,
    }

    impl<Q: Mutex<T = TxQueue>, M: Mutex<T = super::Mailbox>> TxOut<Q, M> {
        /// The command side is alive: the control core's view, its time now the check-in.
        fn check_in(&mut self) -> finger_fw::control::View {
            self.mailbox.lock(|m| {
                m.checkin_ms = m.view.now_ms;
                m.view
            })
        }

        /// Time now in SysTick counts (control ms x `SYSTICK_PER_MS` + the count within the tick).
        fn now_counts(&mut self) -> u64 {
            loop {
                let ms = self.mailbox.lock(|m| m.view.now_ms);
                let c = time::systick_elapsed();
                if self.mailbox.lock(|m| m.view.now_ms) == ms {
                    return ms as u64 * time::SYSTICK_PER_MS as u64 + c as u64;
                }
            }
        }

        /// `reset`: its reply sent (the queue empty, then two ticks for the last byte on the
        /// wire), then the chip's system reset; it boots as at power-up.
        #[cfg(not(m3))]
        fn reboot(&mut self) -> ! {
            while !self.tx.lock(|t| t.is_empty()) {
                self.check_in();
                cortex_m::asm::wfi();
            }
            let t0 = self.check_in().now_ms;
            while self.check_in().now_ms.wrapping_sub(t0) < 2 {
                cortex_m::asm::wfi();
            }
            cortex_m::peripheral::SCB::sys_reset()
        }

        fn flush(&mut self) {
            while !self.tx.lock(|t| t.push_line(&self.line)) {
                self.check_in();
                cortex_m::asm::wfi();
            }
            self.line.clear();
        }
    }

    impl<Q: Mutex<T = TxQueue>, M: Mutex<T = super::Mailbox>> core::fmt::Write for TxOut<Q, M> {
        fn write_str(&mut self, s: &str) -> core::fmt::Result {
            for &b in s.as_bytes() {
                if self.line.push(b).is_err() {
                    self.flush();
                    let _ = self.line.push(b);
                }
                if b == b'\n' {
                    self.flush();
                }
            }
            Ok(())
        }
    }
}
