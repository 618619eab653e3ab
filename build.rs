//! Linker setup for the firmware binary (target only): memory.x, cortex-m-rt's link.x, then
//! memory-m3.x for the Cortex-M3 image (thumbv7m-none-eabi, which also gets `cfg(m3)`: stack
//! placement and its 64 KiB / 20 KiB budget) and defmt's defmt.x (feature `log`). Host builds of the library (host-tests) need none of it.
use std::{env, fs, path::PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=memory-m3.x");
    println!("cargo:rerun-if-changed=build.rs");
    println!("cargo:rustc-check-cfg=cfg(m3)");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let out = PathBuf::from(env::var("OUT_DIR").unwrap());
    let m3 = env::var("TARGET").is_ok_and(|t| t.starts_with("thumbv7m-"));
    if m3 {
        println!("cargo:rustc-cfg=m3");
    }
    fs::copy("memory.x", out.join("memory.x")).unwrap();
    println!("cargo:rustc-link-search={}", out.display());
    if m3 {
        fs::copy("memory-m3.x", out.join("memory-m3.x")).unwrap();
    }
    // the firmware (bins) and the on-target tests (tests/on_target.rs) link alike
    for kind in ["bins", "tests"] {
        println!("cargo:rustc-link-arg-{kind}=--nmagic");
        println!("cargo:rustc-link-arg-{kind}=-Tlink.x");
        if m3 {
            // memory.x: the M3 image's program starts after its vector table, not past the
            // F405's settings sectors
            println!("cargo:rustc-link-arg-{kind}=--defsym=_m3_image=1");
            // the fault-injection test image (tests/qemu_faults) carries the `crash` command,
            // which no shipped image has: its budget is 64 KiB plus that command's 1 KiB
            let slack = if env::var_os("CARGO_FEATURE_FAULT_INJECT").is_some() { 1024 } else { 0 };
            println!("cargo:rustc-link-arg-{kind}=--defsym=_m3_test_slack={slack}");
            println!("cargo:rustc-link-arg-{kind}=-Tmemory-m3.x");
        }
        if env::var_os("CARGO_FEATURE_LOG").is_some() {
            println!("cargo:rustc-link-arg-{kind}=-Tdefmt.x");
        }
    }
}
