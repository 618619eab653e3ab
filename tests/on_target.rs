//! On-target tests (defmt-test): the firmware's library on the STM32F405 itself, in QEMU
//! netduinoplus2. `cargo test` at the top builds this for thumbv7em-none-eabihf and
//! scripts/qemu-run boots it; each test's result comes back over defmt (semihosting), the
//! run's over QEMU's exit code.
//!
//! What runs here and nowhere else: the control core writing the chip's TIM4 compare
//! registers (CCR1..3, the HV modules' duties) through the image's board support
//! (`finger_fw::chip`, stm32f4xx-hal's PWM), read back raw; the console's line ring and the
//! commands as the chip's interrupt and idle task run them; the model's solve in f32 on the
//! M4F (fast-trig, as the firmware builds it). What does not: the RTIC app itself
//! (src/main.rs), which host-tests/tests/qemu_*.rs boot whole.
#![cfg_attr(target_os = "none", no_std)]
#![cfg_attr(target_os = "none", no_main)]

/// On the host there is nothing to run: these tests need the chip.
#[cfg(not(target_os = "none"))]
fn main() {}

#[cfg(target_os = "none")]
mod chip {
    use cortex_m_rt as _;
    use defmt_semihosting as _;
    use finger_fw::chip::f405::{bring_up, F405Board};
    use finger_fw::control::Control;
    use finger_fw::rx::RxLines;
    use finger_fw::Commands;
    use stm32f4xx_hal::pac;

    /// TIM4 CCR1..3: the HV modules' control duties.
    pub const TIM4_CCR: [usize; 3] = [0x4000_0834, 0x4000_0838, 0x4000_083C];

    pub fn ccr(ch: usize) -> u32 {
        // SAFETY: a read of TIM4's compare register on the STM32F405.
        unsafe { core::ptr::read_volatile(TIM4_CCR[ch] as *const u32) }
    }
    pub fn set_ccr(ch: usize, v: u32) {
        // SAFETY: a write of TIM4's compare register (no output is wired in QEMU).
        unsafe { core::ptr::write_volatile(TIM4_CCR[ch] as *mut u32, v) }
    }
    pub fn ccrs() -> [u32; 3] {
        [ccr(0), ccr(1), ccr(2)]
    }

    /// The board brought up anew by the image's own bring-up (each test starts from it).
    pub fn board() -> F405Board {
        // SAFETY: the tests run one after another on one core; each takes the peripherals
        // whole and drops the previous test's board first.
        bring_up(unsafe { pac::Peripherals::steal() }).board
    }

    /// The command side and the control core on the chip's board, as src/main.rs wires them.
    pub struct Rig {
        pub cmds: Commands,
        pub ctl: Control<F405Board>,
        pub rx: RxLines,
    }

    impl Rig {
        pub fn new() -> Rig {
            let (cmds, ctl) = finger_fw::wire(board());
            Rig { cmds, ctl, rx: RxLines::new() }
        }

        /// One console line, through the line ring as the USART interrupt fills it, run by
        /// the command side; its setpoints taken by the core. The reply.
        pub fn line(&mut self, text: &str) -> heapless::String<512> {
            let mut out = heapless::String::<512>::new();
            for &b in text.as_bytes().iter().chain(b"\r\n") {
                if self.rx.push(b) == finger_fw::rx::RxEvent::Stop {
                    self.ctl.stop();
                    self.cmds.sync(&self.ctl.view());
                }
            }
            while let Some(rec) = self.rx.pop() {
                self.cmds.run(rec, &mut out);
                let sp = self.cmds.setpoints();
                self.ctl.apply(&sp);
                self.cmds.sync(&self.ctl.view());
            }
            out
        }

        pub fn tick(&mut self) {
            let now = self.ctl.now_ms();
            self.ctl.tick(now);
            self.cmds.sync(&self.ctl.view());
        }
    }

    /// An `ok` reply.
    pub fn ok(r: &str) -> bool {
        r.starts_with("ok")
    }

    /// A failed test: the panic message over defmt, QEMU exits with 1 (scripts/qemu-run
    /// reports it).
    #[panic_handler]
    fn panic(info: &core::panic::PanicInfo) -> ! {
        defmt::error!("{}", defmt::Display2Format(info));
        semihosting::process::exit(1)
    }

    #[cortex_m_rt::exception]
    unsafe fn HardFault(_: &cortex_m_rt::ExceptionFrame) -> ! {
        defmt::error!("HardFault");
        semihosting::process::exit(1)
    }
}

#[cfg(target_os = "none")]
#[defmt_test::tests]
mod tests {
    use super::chip::{ccr, ccrs, ok, set_ccr, Rig};
    use core::fmt::Write;
    use finger_fw::control::{hv_duty_cap, hv_duty_for};
    use finger_fw::rx::{Record, RxEvent, RxLines, RX_RING};
    use finger_model::{Finger, Method, Params};

    /// The control core takes the board with every HV duty at 0, whatever the compare
    /// registers held, and keeps them there while disarmed.
    #[test]
    fn hv_duty_registers_read_0_after_init() {
        for ch in 0..3 {
            set_ccr(ch, 0x1234);
        }
        assert_eq!(ccrs(), [0x1234; 3], "TIM4 CCR1..3 take writes");
        let mut rig = Rig::new();
        assert_eq!(ccrs(), [0; 3]);
        let v = rig.ctl.view();
        assert!(!v.enable);
        assert_eq!(v.duty, [0; 3]);
        for _ in 0..50 {
            rig.tick();
        }
        assert_eq!(ccrs(), [0; 3]);
        let r = rig.line("volt 1 100");
        assert!(r.starts_with("err not-armed"), "{}", r.as_str());
        rig.tick();
        assert_eq!(ccrs(), [0; 3]);
    }

    /// Armed, a voltage step reaches the chip at the slew rate: each tick the compare
    /// register moves at most one slew step's duty, ends at the target's duty, and always
    /// reads what the core reports.
    #[test]
    fn control_tick_slews_the_duty_register() {
        let mut rig = Rig::new();
        assert!(ok(&rig.line("arm")));
        let max = rig.ctl.hv_max()[0];
        let slew = rig.cmds.fw_params().slew;
        let target = (0.5 * rig.cmds.vmax()[0]) as u32;
        let mut cmd = heapless::String::<32>::new();
        write!(cmd, "volt 1 {}", target).unwrap();
        let r = rig.line(&cmd);
        assert!(ok(&r), "{}", r.as_str());
        let want = hv_duty_for(target as f32, max) as u32;
        let step = hv_duty_for(slew * 1e-3, max) as u32 + 1;
        assert!(want > 4 * step, "the step takes several ticks");
        let mut last = ccr(0);
        let mut ticks = 0;
        while ccr(0) != want {
            rig.tick();
            ticks += 1;
            let now = ccr(0);
            assert!(now >= last && now - last <= step, "tick {}: {} -> {} (step {})", ticks, last, now, step);
            assert_eq!(now, rig.ctl.view().duty[0] as u32);
            assert!(ticks <= 2 * (target as f32 / (slew * 1e-3)) as u32 + 2, "slew too slow");
            last = now;
        }
        let expect = (target as f32 / (slew * 1e-3)) as u32;
        assert!(ticks + 1 >= expect && ticks <= expect + 1, "{} ticks for {} V at {} V/s", ticks, target, slew);
        assert_eq!([ccr(1), ccr(2)], [0, 0]);
    }

    /// Above the ceiling nothing reaches the chip: the console refuses the voltage, the
    /// core's single writer refuses the duty (and latches a fault), and setpoints past the
    /// ceiling stop the HV at once.
    #[test]
    fn control_clamps_the_duty_at_the_ceiling() {
        let mut rig = Rig::new();
        assert!(ok(&rig.line("arm")));
        let max = rig.ctl.hv_max()[0];
        // the command side's ceiling, tightened by the board's hold ceiling
        let ceiling = rig.cmds.duty_ceiling()[0].min(hv_duty_for(rig.ctl.hold_ceiling_v(), max));
        assert!(ceiling > 0 && ceiling <= hv_duty_cap(max));
        let mut cmd = heapless::String::<32>::new();
        write!(cmd, "volt 1 {}", (rig.cmds.vmax()[0] * 1.01) as u32 + 1).unwrap();
        let r = rig.line(&cmd);
        assert!(r.starts_with("err limit"), "{}", r.as_str());
        for _ in 0..20 {
            rig.tick();
        }
        assert_eq!(ccrs(), [0; 3]);
        assert!(rig.ctl.write_hv_duty(0, ceiling + 1).is_err());
        assert_eq!(ccr(0), 0);
        assert_eq!(rig.ctl.view().fault, Some("hv-refused"));
        assert!(rig.ctl.write_hv_duty(0, ceiling).is_ok(), "at the ceiling is allowed");
        assert_eq!(ccr(0), ceiling as u32);
        let mut sp = rig.cmds.setpoints();
        sp.armed = true;
        sp.target_v[1] = rig.cmds.vmax()[1] * 1.5;
        rig.ctl.apply(&sp);
        assert_eq!(ccrs(), [0; 3], "setpoints past the ceiling: HV off at once");
        assert!(!rig.ctl.view().enable);
    }

    /// `stop` arriving on the line ring turns the HV off before the next tick.
    #[test]
    fn stop_zeroes_the_duty_registers_at_once() {
        let mut rig = Rig::new();
        assert!(ok(&rig.line("arm")));
        assert!(ok(&rig.line("volt all 500")));
        for _ in 0..300 {
            rig.tick();
        }
        assert!(ccrs().iter().all(|&d| d > 0), "{:?}", ccrs());
        let mut rx = RxLines::new();
        let mut ev = RxEvent::Nothing;
        for &b in b"STOP\r" {
            ev = rx.push(b);
        }
        assert_eq!(ev, RxEvent::Stop);
        rig.ctl.stop();
        assert_eq!(ccrs(), [0; 3]);
        assert!(rx.pop().is_none(), "stop acts, it is not queued");
    }

    /// The stacks in time on the M4F (f32): under a held voltage the predicted thickness falls
    /// as the film creeps, never below `s_hold`; after `stop` (duties 0 at once) it jumps back
    /// part of the way and keeps recovering, tick by tick.
    #[test]
    fn control_tick_integrates_the_film() {
        let mut rig = Rig::new();
        assert!(ok(&rig.line("arm")));
        let v = (0.9 * rig.ctl.hold_ceiling_v()) as u32;
        let mut cmd = heapless::String::<32>::new();
        write!(cmd, "volt 1 {}", v).unwrap();
        assert!(ok(&rig.line(&cmd)));
        let s = |rig: &Rig| rig.ctl.view().stack_ratio[0];
        assert_eq!(s(&rig), 1.0, "at rest");
        let run = |rig: &mut Rig, ms: u32| {
            for _ in 0..ms {
                rig.tick();
                assert!(s(rig) >= rig.ctl.s_hold());
            }
            s(rig)
        };
        // the slew (about 2.4 s at 2 kV/s), then the creep
        let s3 = run(&mut rig, 3_000);
        assert!(s3 < 0.99 && ccr(0) > 0, "thinned under {} V: {}", v, s3);
        let s20 = run(&mut rig, 17_000);
        assert!(s20 < s3 - 0.005, "creeps at a held voltage: {} -> {}", s3, s20);
        assert_eq!(rig.ctl.view().stack_ratio[1], 1.0, "channel 2 at 0 V stays at rest");
        rig.ctl.stop();
        assert_eq!(ccrs(), [0; 3]);
        let s_off = run(&mut rig, 1);
        assert!(s_off > s20 && s_off < 1.0, "part of the way back at once: {}", s_off);
        let s_later = run(&mut rig, 10_000);
        assert!(s_later > s_off, "recovers in time: {} -> {}", s_off, s_later);
    }

    /// The console's line ring on the chip: lines in order, lowercased; a full ring loses
    /// whole lines, counted, never a partial one.
    #[test]
    fn usart_line_ring_keeps_whole_lines() {
        let mut rx = RxLines::new();
        for &b in b"Status\r\nversion\nhelp\r" {
            assert_eq!(rx.push(b), RxEvent::Nothing);
        }
        let mut lines = 0;
        while let Some(r) = rx.pop() {
            let want: &[u8] = [b"status".as_slice(), b"version", b"help"][lines];
            assert_eq!(r, Record::Line(heapless::Vec::from_slice(want).unwrap()));
            lines += 1;
        }
        assert_eq!(lines, 3);
        let line = b"limits 1 2 3 4 5 6 7 8\n";
        let fit = RX_RING / (line.len() - 1 + 2);
        for _ in 0..fit + 10 {
            for &b in line {
                rx.push(b);
            }
        }
        let (mut whole, mut lost) = (0, 0u32);
        while let Some(r) = rx.pop() {
            match r {
                Record::Line(l) => {
                    assert_eq!(&l[..], &line[..line.len() - 1]);
                    whole += 1;
                }
                Record::Overrun(n) => lost += n,
                Record::TooLong => panic!("no line was too long"),
                Record::Stopped(_) => panic!("no stop was sent"),
            }
        }
        assert!(whole <= fit && whole + 1 >= fit, "{} whole lines, {} fit", whole, fit);
        assert_eq!(whole as u32 + lost, fit as u32 + 10);
    }

    /// The model on the M4F (f32, the firmware's trig): the converged solve is in
    /// equilibrium, bends further with more tension, and further with the stacks at a
    /// voltage (thinned, softer) than at 0 V.
    #[test]
    fn model_solve_on_target() {
        let f = Finger::<f32>::new(Params::default()).unwrap();
        let v_on = [0.6 * f.voltage_ceiling(); 3];
        let mut last = 0.0f32;
        for i in 1..=5 {
            let p = 0.2 * i as f32;
            let s = f.solve(p, &[0.0; 3], Method::converged()).unwrap();
            let tip = s.tip().theta;
            assert!(tip.is_finite() && tip > last, "tip angle {} at {} N after {}", tip, p, last);
            let res = f.equilibrium_residual(&s).unwrap();
            assert!(res < 1e-4, "relative wrench imbalance {} at {} N", res, p);
            let soft = f.solve(p, &v_on, Method::converged()).unwrap();
            assert!(soft.tip().theta > tip, "{} V: {} <= {}", v_on[0], soft.tip().theta, tip);
            last = tip;
        }
    }
}
