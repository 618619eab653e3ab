//! What the client's tests share: the finger-sim and firmware images they drive (each built
//! once per test binary) and the `finger` program itself.
#![allow(dead_code)]
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("../..").canonicalize().unwrap()
}

pub fn cargo() -> String {
    std::env::var("CARGO").unwrap_or_else(|_| "cargo".into())
}

/// finger-sim, built once (tools/finger-sim, for this machine).
pub fn sim() -> &'static Path {
    static SIM: OnceLock<PathBuf> = OnceLock::new();
    SIM.get_or_init(|| {
        let out = Command::new(cargo())
            .current_dir(root().join("tools/finger-sim"))
            .args(["build", "--quiet", "--bin", "finger-sim", "--message-format", "short"])
            .output()
            .expect("cargo");
        assert!(out.status.success(), "finger-sim build failed:\n{}", String::from_utf8_lossy(&out.stderr));
        // next to this test's own `finger` binary: same target dir and profile layout
        let exe = PathBuf::from(env!("CARGO_BIN_EXE_finger"));
        let p = exe.parent().unwrap().join("finger-sim");
        assert!(p.exists(), "finger-sim not at {}", p.display());
        p
    })
}

/// The emulator firmware image, built once (`cargo build --release` at the top).
pub fn image() -> &'static Path {
    static IMG: OnceLock<PathBuf> = OnceLock::new();
    IMG.get_or_init(|| {
        let out = Command::new(cargo())
            .current_dir(root())
            .args(["build", "--release", "--quiet", "--bin", "finger-fw"])
            .output()
            .expect("cargo");
        assert!(out.status.success(), "firmware build failed:\n{}", String::from_utf8_lossy(&out.stderr));
        let p = root().join("target/thumbv7em-none-eabihf/release/finger-fw");
        assert!(p.exists());
        p
    })
}

pub fn finger(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_finger")).args(args).output().expect("finger")
}

pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}
