//! fw-size: flash and static RAM of a firmware ELF (default: the release image).
//! Flash = every allocated section loaded from flash (vector table, .text, .rodata, .data's
//! initial values); static RAM = .data + .bss + .uninit (the stack is not counted).
//!
//! Usage (from host-tests/; scripts/fw-size wraps it):
//!   cargo run --bin fw-size [-- path/to/elf]            flash and RAM
//!   cargo run --bin fw-size -- --symbols N [elf]        ... and the N largest symbols
//!   cargo run --bin fw-size -- --table [out.md]         builds every feature set of the
//!       firmware (lean builds, issue 5) and prints (or writes) the flash/RAM table
use std::path::{Path, PathBuf};
use std::process::Command;

use object::{Object, ObjectSection, ObjectSymbol, SectionFlags, SymbolKind};

fn root() -> PathBuf {
    Path::new(env!("CARGO_MANIFEST_DIR")).join("..").canonicalize().unwrap()
}

fn target_dir() -> PathBuf {
    match std::env::var_os("CARGO_TARGET_DIR") {
        Some(d) if Path::new(&d).is_absolute() => PathBuf::from(d),
        Some(d) => std::env::current_dir().unwrap().join(d),
        None => root().join("target"),
    }
}

fn default_elf() -> PathBuf {
    target_dir().join("thumbv7em-none-eabihf/release/finger-fw")
}

/// (flash bytes, static RAM bytes) of an ELF.
fn sizes(data: &[u8]) -> (u64, u64) {
    let elf = object::File::parse(data).expect("ELF");
    let (mut flash, mut ram) = (0u64, 0u64);
    for s in elf.sections() {
        let alloc = matches!(s.flags(), SectionFlags::Elf { sh_flags } if sh_flags & 0x2 != 0);
        if !alloc || s.size() == 0 {
            continue;
        }
        let name = s.name().unwrap_or("");
        let addr = s.address();
        let in_ram = (0x2000_0000..0x2002_0000).contains(&addr);
        if in_ram {
            ram += s.size();
            if name == ".data" {
                flash += s.size();
            }
        } else if (0x0800_0000..0x0810_0000).contains(&addr) {
            flash += s.size();
        }
    }
    (flash, ram)
}

fn read(path: &Path) -> Vec<u8> {
    std::fs::read(path).unwrap_or_else(|e| panic!("{}: {e} (build it: cargo build --release at the top)", path.display()))
}

/// The firmware's feature sets: (name, cargo features, what the image holds).
const SETS: &[(&str, &str, &str)] = &[
    ("full (default)", "qemu,full", "console, defmt, model with DE, pose, contact"),
    ("full, board", "hw,full", "as above, hardware build (PLL, IWDG, RTT)"),
    ("no contact", "qemu,de,pose,log", "console, defmt, DE, pose"),
    ("no pose", "qemu,de,contact,log", "console, defmt, DE, contact"),
    ("forward only", "qemu,de,log", "console, defmt, DE; solve/force/volt/limits"),
    ("forward, no defmt", "qemu,de", "console, DE"),
    ("forward, no DE, no defmt", "qemu", "console, finger without stacks (layers = 0)"),
];
/// The Cortex-M3 image (thumbv7m-none-eabi, QEMU netduino2): its RAM includes its 16 KiB stack
/// section (memory-m3.x).
const M3_SET: (&str, &str, &str) = ("Cortex-M3 (thumbv7m, netduino2)", "m3", "console, defmt, DE, `pose`; fixed-point model; RAM with its 16 KiB stack (budget 64 KiB / 20 KiB)");

fn build(features: &str) -> PathBuf {
    build_for(features, None)
}

/// Build with `features` for `target` (None: the package's default, the F405's).
fn build_for(features: &str, target: Option<&str>) -> PathBuf {
    let cargo = std::env::var("CARGO").unwrap_or_else(|_| "cargo".into());
    let mut c = Command::new(cargo);
    c.current_dir(root()).env("CARGO_TARGET_DIR", target_dir()).args(["build", "--release", "--quiet", "--bin", "finger-fw", "--no-default-features", "--features", features]);
    if let Some(t) = target {
        c.args(["--target", t]);
    }
    let st = c.status().expect("cargo");
    assert!(st.success(), "firmware build with features {features} failed");
    match target {
        Some(t) => target_dir().join(t).join("release/finger-fw"),
        None => default_elf(),
    }
}

fn table() -> String {
    let mut t = String::new();
    t.push_str("| image | cargo features | holds | flash bytes | flash KiB | static RAM bytes |\n");
    t.push_str("| --- | --- | --- | ---: | ---: | ---: |\n");
    for (name, feats, holds) in SETS {
        let (flash, ram) = sizes(&read(&build(feats)));
        eprintln!("{name}: flash={flash} ram={ram}");
        t.push_str(&format!("| {name} | `{feats}` | {holds} | {flash} | {:.1} | {ram} |\n", flash as f64 / 1024.0));
    }
    let (name, feats, holds) = M3_SET;
    let (flash, ram) = sizes(&read(&build_for(feats, Some("thumbv7m-none-eabi"))));
    eprintln!("{name}: flash={flash} ram={ram}");
    t.push_str(&format!("| {name} | `{feats}` | {holds} | {flash} | {:.1} | {ram} |\n", flash as f64 / 1024.0));
    build("qemu,full"); // leave the default image in place
    t
}

fn main() {
    let args: Vec<String> = std::env::args().skip(1).collect();
    if args.first().map(String::as_str) == Some("--table") {
        let t = table();
        match args.get(1) {
            None => print!("{t}"),
            Some(out) => {
                let doc = format!(
                    "# Firmware size per feature set (lean builds)\n\n\
                     Generated by `scripts/fw-size --table` (host-tests' `fw-size --table`): each feature set of the\n\
                     firmware package built with `cargo build --release --no-default-features --features <set>`\n\
                     (profile: opt-level \"z\", fat LTO, one codegen unit, panic = abort). Flash: vector table,\n\
                     .text, .rodata and .data's load image; static RAM: .data + .bss + .uninit (the stack is not\n\
                     counted). The STM32F405 (1 MiB flash, 192 KiB RAM) sets no budget below its chip.\n\
                     See docs/firmware.md (\"Size\") for what the numbers are made of.\n\n{t}"
                );
                std::fs::write(out, doc).unwrap_or_else(|e| panic!("{out}: {e}"));
                println!("wrote {out}");
            }
        }
        return;
    }
    let (nsym, rest) = match args.first().map(String::as_str) {
        Some("--symbols") => (args.get(1).and_then(|n| n.parse().ok()).expect("--symbols N"), &args[2..]),
        _ => (0usize, &args[..]),
    };
    let path = rest.first().map(PathBuf::from).unwrap_or_else(default_elf);
    let data = read(&path);
    let (flash, ram) = sizes(&data);
    println!("{}", path.display());
    // the Cortex-M3 image's budget is its linker script's (memory-m3.x): its RAM sections
    // include the stack
    let m3 = path.to_string_lossy().contains("thumbv7m-none-eabi");
    let (fb, rb) = if m3 { ("M3 budget 64 KiB", "with the stack; M3 budget 20 KiB") } else { ("target <= 64 KiB", "target <= 16 KiB") };
    println!("flash={flash} bytes ({:.1} KiB, {fb})", flash as f64 / 1024.0);
    println!("ram={ram} bytes static ({:.1} KiB, {rb})", ram as f64 / 1024.0);
    if nsym > 0 {
        let elf = object::File::parse(&*data).expect("ELF");
        let mut syms: Vec<(u64, String)> = elf
            .symbols()
            .filter(|s| matches!(s.kind(), SymbolKind::Text | SymbolKind::Data) && s.size() > 0)
            .map(|s| (s.size(), s.name().unwrap_or("?").to_owned()))
            .collect();
        syms.sort();
        syms.dedup();
        println!("largest symbols (bytes, mangled names; inlined code counts to its caller):");
        for (size, name) in syms.iter().rev().take(nsym) {
            println!("{size:>8}  {name}");
        }
    }
}
