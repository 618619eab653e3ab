//! What the client's tests share: the finger-sim and firmware images they drive (each built
//! once per test binary; the firmware's by the test harness, host-tests/src/image.rs) and the
//! `finger` program itself.
#![allow(dead_code)]
use std::path::{Path, PathBuf};
use std::process::{Command, Output};
use std::sync::OnceLock;

pub use host_tests::image::{image, root};

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

/// An empty scratch directory for one test, `finger-<what>-<pid>` under the temporary directory.
pub fn scratch(what: &str) -> PathBuf {
    let d = std::env::temp_dir().join(format!("finger-{what}-{}", std::process::id()));
    let _ = std::fs::remove_dir_all(&d);
    std::fs::create_dir_all(&d).unwrap();
    d
}

/// A board stand-in: `body` as an executable shell script at `path`.
pub fn shell_board(path: &Path, body: &str) {
    std::fs::write(path, format!("#!/bin/sh\n{body}\n")).unwrap();
    std::fs::set_permissions(path, std::os::unix::fs::PermissionsExt::from_mode(0o755)).unwrap();
}

pub fn finger(args: &[&str]) -> Output {
    Command::new(env!("CARGO_BIN_EXE_finger")).args(args).output().expect("finger")
}

pub fn text(b: &[u8]) -> String {
    String::from_utf8_lossy(b).into_owned()
}
