//! The images the tests and reports run, built with cargo: [`cargo_build`], the one
//! `cargo build` of a binary for a target with a feature set, and [`Image`], the firmware's
//! emulator images (each built once per process). Used by the QEMU tests ([`crate::qemu`]),
//! the bench runs ([`crate::perf`]), `fw-size`, the reports and tools/finger's tests.
use std::path::{Path, PathBuf};
use std::process::Command;
use std::sync::OnceLock;

/// The firmware package's directory (the repository's top).
pub fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").canonicalize().unwrap()
}

/// Where cargo puts builds: $CARGO_TARGET_DIR if set (relative to the current directory),
/// else `default`.
pub fn cargo_target_dir(default: PathBuf) -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(d) if Path::new(&d).is_absolute() => PathBuf::from(d),
        Some(d) => std::env::current_dir().unwrap_or_default().join(d),
        None => default,
    }
}

/// Where the firmware's builds go: $CARGO_TARGET_DIR if set, else target/ at the top.
pub fn target_dir() -> PathBuf {
    cargo_target_dir(root().join("target"))
}

/// One `cargo build --release` of a binary.
pub struct CargoBuild<'a> {
    /// The package's directory.
    pub dir: PathBuf,
    pub bin: &'a str,
    /// The target triple.
    pub target: &'a str,
    /// `--no-default-features --features <these>`; None: the package's default features.
    pub features: Option<&'a str>,
    /// Where the build goes (`CARGO_TARGET_DIR`).
    pub target_dir: PathBuf,
    /// Build-time variables: each (name, Some(value)) set, each (name, None) removed.
    pub env: &'a [(&'a str, Option<&'a str>)],
}

/// Run the build; the ELF's path, or cargo's errors.
pub fn cargo_build(b: &CargoBuild) -> Result<PathBuf, String> {
    let mut c = Command::new(std::env::var("CARGO").unwrap_or_else(|_| "cargo".into()));
    for (k, v) in b.env {
        match v {
            Some(v) => c.env(k, v),
            None => c.env_remove(k),
        };
    }
    c.current_dir(&b.dir).env("CARGO_TARGET_DIR", &b.target_dir);
    c.args(["build", "--release", "--quiet", "--bin", b.bin, "--target", b.target]);
    if let Some(f) = b.features {
        c.args(["--no-default-features", "--features", f]);
    }
    let out = c.output().map_err(|e| format!("cargo: {e}"))?;
    if !out.status.success() {
        return Err(format!("build of {} ({}, features {:?}) failed:\n{}", b.bin, b.target, b.features, String::from_utf8_lossy(&out.stderr)));
    }
    Ok(b.target_dir.join(b.target).join("release").join(b.bin))
}

/// The firmware (`finger-fw`) for `target` with exactly `features`, into `tdir`; its path.
pub fn build_firmware(target: &str, features: &str, tdir: PathBuf) -> PathBuf {
    let b = CargoBuild { dir: root(), bin: "finger-fw", target, features: Some(features), target_dir: tdir, env: &[] };
    cargo_build(&b).unwrap_or_else(|e| panic!("firmware {e}"))
}

/// One `#[test]` per image for each `test => check;` (`check(Image)`): `m4f::test` and
/// `m3::test`, in the test file that invokes it.
#[macro_export]
macro_rules! on_both_images {
    ($($name:ident => $check:ident;)*) => {
        mod m4f {
            $(#[test]
            fn $name() {
                super::$check($crate::image::Image::M4f);
            })*
        }
        mod m3 {
            $(#[test]
            fn $name() {
                super::$check($crate::image::Image::M3);
            })*
        }
    };
}

/// The firmware's emulator images the QEMU tests run against.
#[derive(Clone, Copy, Debug, PartialEq, Eq)]
pub enum Image {
    /// The F405's image (`cargo build --release`): Cortex-M4F, QEMU netduinoplus2.
    M4f,
    /// The Cortex-M3 image (`--target thumbv7m-none-eabi --features m3`): no FPU, QEMU
    /// netduino2 (an STM32F205), 64 KiB of flash; the fixed-point model, `pose` at a given
    /// tension only, no `contact` (docs/firmware.md).
    M3,
}

impl Image {
    pub const ALL: [Image; 2] = [Image::M4f, Image::M3];
    pub fn target(self) -> &'static str {
        match self {
            Image::M4f => "thumbv7em-none-eabihf",
            Image::M3 => "thumbv7m-none-eabi",
        }
    }
    /// QEMU's `-machine` and `-cpu`.
    pub fn machine(self) -> [&'static str; 2] {
        match self {
            Image::M4f => ["netduinoplus2", "cortex-m4"],
            Image::M3 => ["netduino2", "cortex-m3"],
        }
    }
    /// The board name `version` reports.
    pub fn board(self) -> &'static str {
        match self {
            Image::M4f => "qemu-netduinoplus2",
            Image::M3 => "qemu-netduino2",
        }
    }
    /// The image reads its HV back (its plant) and closes the voltage loop on it.
    pub fn reads_hv_back(self) -> bool {
        self == Image::M4f
    }
    /// The image has `pose` and `contact` (feature `full`).
    pub fn has_inverse(self) -> bool {
        self == Image::M4f
    }
    /// QEMU models the STM32's RCC and GPIO on this machine (as unimplemented devices that the
    /// trace shows with their values); netduino2 does not: those writes are logged without a
    /// value (`Access::modelled` false).
    pub fn models_gpio(self) -> bool {
        self == Image::M4f
    }
    /// The image's cargo features (the package's default set for the F405's), with `extra`.
    fn features(self, extra: &str) -> String {
        let base = match self {
            Image::M4f => "qemu,full",
            Image::M3 => "m3",
        };
        [base, extra].iter().filter(|f| !f.is_empty()).copied().collect::<Vec<_>>().join(",")
    }
    /// Build the image (extra `features`) in `tdir`; its path.
    fn build(self, extra: &str, tdir: PathBuf) -> PathBuf {
        build_firmware(self.target(), &self.features(extra), tdir)
    }
    /// The release image, built once per process.
    pub fn elf(self) -> &'static Path {
        static IMG: [OnceLock<PathBuf>; 2] = [OnceLock::new(), OnceLock::new()];
        IMG[self as usize].get_or_init(|| self.build("", target_dir()))
    }
    /// The image with its stack painted at reset (cortex-m-rt `paint-stack`; its own target
    /// dir): `Qemu::stack_high_water` reads how deep the stack went.
    pub fn paint_elf(self) -> &'static Path {
        static IMG: [OnceLock<PathBuf>; 2] = [OnceLock::new(), OnceLock::new()];
        IMG[self as usize].get_or_init(|| self.build("cortex-m-rt/paint-stack", target_dir().join("paint")))
    }
    /// The image with the `fault-inject` test command (its own target dir).
    pub fn fault_elf(self) -> &'static Path {
        static IMG: [OnceLock<PathBuf>; 2] = [OnceLock::new(), OnceLock::new()];
        IMG[self as usize].get_or_init(|| self.build("fault-inject", target_dir().join("faults")))
    }
    /// The image an ELF was built as (by its target's directory).
    pub fn of(elf: &Path) -> Image {
        if elf.to_string_lossy().contains(Image::M3.target()) {
            Image::M3
        } else {
            Image::M4f
        }
    }
}

/// The F405 emulator image, built once per process; its path.
pub fn image() -> &'static Path {
    Image::M4f.elf()
}

/// The F405 emulator image with the `fault-inject` test command (its own target dir).
pub fn fault_image() -> &'static Path {
    Image::M4f.fault_elf()
}
