//! Every fault path turns the HV off first (issue 12), in QEMU from the register trace: a
//! test image (feature `fault-inject`: `crash <what>`) takes a HardFault, an NMI, an
//! unhandled interrupt (DefaultHandler) and a stack overflow (the MPU guard) while channel
//! voltages are up; each time GPIOB BSRR drives PB6-8 and PB12 low and TIM4 CCR1..3 are
//! written 0, and no control tick runs after (the handler halts; on the board the IWDG resets).
use host_tests::qemu::{fault_image, Qemu, TICK_MARKER, TIM4_CCR};

#[test]
fn every_fault_path_turns_hv_off() {
    for what in ["hardfault", "nmi", "irq", "overflow"] {
        let mut q = Qemu::boot_image(fault_image(), what);
        assert_eq!(q.cmd("arm"), "ok armed=1");
        assert!(q.cmd("volt all 3000").starts_with("ok volts="));
        assert_eq!(q.cmd("wait 1"), "ok waited=1");
        q.write(format!("crash {what}\r\n").as_bytes());
        std::thread::sleep(std::time::Duration::from_millis(500));
        let trace = q.finish();
        let w: Vec<_> = trace.iter().filter(|a| a.write).collect();
        // the last duty written before the fault was the ramp's (2000 V, non-zero)
        let off = w.iter().rposition(|a| a.addr == 0x4002_0418 && a.value == 0x11C0_0000).expect("HV-off store");
        assert!(w[..off].iter().any(|a| a.addr == TIM4_CCR[0] && a.value > 0), "{what}: HV was on");
        // then MODER (outputs), CCR1..3 = 0, in that order, nothing between
        assert_eq!(w[off + 1].addr, 0x4002_0400, "{what}");
        for (k, &r) in TIM4_CCR.iter().enumerate() {
            assert_eq!((w[off + 2 + k].addr, w[off + 2 + k].value), (r, 0), "{what}");
        }
        // halted: no tick after
        assert!(!w[off..].iter().any(|a| a.addr == TICK_MARKER), "{what}: ticks ran after the fault");
    }
}
