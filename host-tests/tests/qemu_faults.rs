//! Every fault path turns the HV off first, in QEMU from the register trace: a
//! test image (feature `fault-inject`: `crash <what>`) takes a HardFault, an NMI, an
//! unhandled interrupt (DefaultHandler) and a stack overflow (the MPU guard) while channel
//! voltages are up; each time GPIOB BSRR drives PB6-8 and PB12 low and TIM4 CCR1..3 are
//! written 0, and no control tick runs after (the handler halts; on the board the IWDG resets).
//! Against both images: the F405's and the Cortex-M3 image (netduino2, where GPIOB is not
//! modelled: its writes are checked in order, without their values; the guard is below SRAM).
use host_tests::image::Image;
use host_tests::qemu::{parse_trace, Qemu, TICK_MARKER, TIM4_CCR};

host_tests::on_both_images! {
    every_fault_path_turns_hv_off => every_fault_path;
}

fn every_fault_path(img: Image) {
    for what in ["hardfault", "nmi", "irq", "overflow"] {
        // QEMU's exception log (-d int) goes into the trace file too
        let mut q = Qemu::boot_traced_with(img.fault_elf(), what, &["-d", "int"]);
        assert_eq!(q.cmd("arm"), "ok armed=1");
        assert!(q.cmd("volt all 3000").starts_with("ok volts="));
        assert_eq!(q.cmd("wait 1"), "ok waited=1");
        q.write(format!("crash {what}\r\n").as_bytes());
        std::thread::sleep(std::time::Duration::from_millis(500));
        let log = q.finish_log();
        let trace = parse_trace(&log);
        if what == "overflow" {
            // caught by the MPU guard (a MemManage access violation inside it, 16 KiB above
            // the statics; below SRAM on the M3 image), not by running through them; the HardFault
            // handler is still entered (no lockup) although the stacking failed
            let mmfar = log
                .lines()
                .find_map(|l| l.split("CFSR.DACCVIOL and MMFAR 0x").nth(1))
                .map(|h| u64::from_str_radix(h.trim(), 16).unwrap())
                .expect("an MPU access violation");
            // the guard's base, as the firmware wrote it to MPU_RBAR (16 KiB, no access)
            let base = trace.iter().find(|a| a.write && a.addr == 0xE000_ED9C).expect("MPU_RBAR written").value & !0x1F;
            assert!((base..base + 0x4000).contains(&mmfar), "MMFAR {mmfar:#x} outside the guard at {base:#x}");
            assert!(log.contains("loading from element 3 of non-secure vector table"), "HardFault taken");
        }
        let w: Vec<_> = trace.iter().filter(|a| a.write).collect();
        // the last duty written before the fault was the ramp's (2000 V, non-zero)
        let off = w.iter().rposition(|a| a.writes(0x4002_0418, 0x11C0_0000)).expect("HV-off store");
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
