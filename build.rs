//! Linker setup for the firmware binary (target only): memory.x, cortex-m-rt's link.x and
//! defmt's defmt.x (feature `log`). Host builds of the library (host-tests) need none of it.
use std::{env, fs, path::PathBuf};

fn main() {
    println!("cargo:rerun-if-changed=memory.x");
    println!("cargo:rerun-if-changed=build.rs");
    if env::var("CARGO_CFG_TARGET_OS").as_deref() != Ok("none") {
        return;
    }
    let out = PathBuf::from(env::var("OUT_DIR").unwrap());
    fs::copy("memory.x", out.join("memory.x")).unwrap();
    println!("cargo:rustc-link-search={}", out.display());
    // the firmware (bins) and the on-target tests (tests/on_target.rs) link alike
    for kind in ["bins", "tests"] {
        println!("cargo:rustc-link-arg-{kind}=--nmagic");
        println!("cargo:rustc-link-arg-{kind}=-Tlink.x");
        if env::var_os("CARGO_FEATURE_LOG").is_some() {
            println!("cargo:rustc-link-arg-{kind}=-Tdefmt.x");
        }
    }
}
