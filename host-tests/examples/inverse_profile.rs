//! Where the tabled inverse's instructions go on the Cortex-M4F: builds the bench
//! image `bench/src/bin/table.rs` with its `profile` feature (one `solve_pose_tabled_into`
//! between the markers `profile_start` and `profile_stop`), runs it in QEMU netduinoplus2 with
//! `-icount shift=0 -singlestep -d exec,nochain` (one log line per instruction executed), and
//! attributes every instruction between the markers to the innermost model function that
//! holds it (`addr2line -i` on the image's debug info). Writes docs/inverse-profile.md.
//!
//! `cd host-tests && cargo run --release --example inverse_profile`

use host_tests::perf::{build_with_env, M4F};
use std::collections::{BTreeMap, HashMap};
use std::fmt::Write as _;
use std::path::{Path, PathBuf};
use std::process::Command;

/// One profiled case: its name and the build-time variables that select it in table.rs.
struct Case {
    name: &'static str,
    env: &'static [&'static str],
}

const CASES: &[Case] = &[
    Case { name: "three different joints, tension given", env: &["PROFILE_HARD", "PROFILE_INVERSE"] },
    Case { name: "three different joints, tension free", env: &["PROFILE_HARD", "PROFILE_INVERSE", "PROFILE_FREE"] },
    Case { name: "identical joints, tension given", env: &["PROFILE_HARD", "PROFILE_INVERSE", "PROFILE_SAME"] },
    Case { name: "identical joints, tension free", env: &["PROFILE_HARD", "PROFILE_INVERSE", "PROFILE_SAME", "PROFILE_FREE"] },
    Case { name: "m = 1 (the paper's finger), three different joints, tension given", env: &["PROFILE_HARD", "PROFILE_INVERSE", "PROFILE_M1"] },
    Case { name: "m = 1 (the paper's finger), three different joints, tension free", env: &["PROFILE_HARD", "PROFILE_INVERSE", "PROFILE_M1", "PROFILE_FREE"] },
];

/// The parts the report groups functions into: a name and the function-name fragments it holds
/// (the first part whose fragment a function's name contains; else "the rest").
const PARTS: &[(&str, &[&str])] = &[
    ("march of the full model", &["march", "turn", "Frame", "equilibrium", "advance", "loads"]),
    ("stack stiffness and compliances", &["compliance", "comp_into", "stack_upper", "StackUpper", "StackStiffness", "stack_at", "stack_stiffness", "e_de"]),
    ("table reading", &["BranchTable", "level_guess"]),
    ("voltage", &["voltage", "check_below"]),
];

fn build(case: &Case) -> PathBuf {
    let env: Vec<(&str, Option<&str>)> =
        ["PROFILE_HARD", "PROFILE_INVERSE", "PROFILE_FREE", "PROFILE_SAME", "PROFILE_M1"].iter().map(|v| (*v, case.env.contains(v).then_some("1"))).collect();
    let name = format!("profile-{}", case.env.join("-").to_lowercase());
    build_with_env("table", M4F, "de,fast-trig,table,profile", &name, &env).unwrap_or_else(|e| panic!("{e}"))
}

/// A symbol's (address, size) from `nm -S` (the Thumb bit cleared).
fn symbol(elf: &Path, name: &str) -> (u64, u64) {
    let out = Command::new("nm").arg("-S").arg(elf).output().expect("nm (binutils)");
    let text = String::from_utf8_lossy(&out.stdout);
    for l in text.lines() {
        let f: Vec<&str> = l.split_whitespace().collect();
        if f.len() == 4 && f[3] == name {
            let a = u64::from_str_radix(f[0], 16).unwrap() & !1;
            return (a, u64::from_str_radix(f[1], 16).unwrap());
        }
    }
    panic!("{name} not in {}", elf.display());
}

/// The program counters executed between the markers, in order.
fn trace(elf: &Path) -> Vec<u64> {
    let log = std::env::temp_dir().join(format!("finger-profile-{}.log", std::process::id()));
    let st = host_tests::qemu::qemu_command("netduinoplus2", "shift=0", elf, Some(300))
        .args(["-nographic", "-singlestep", "-d", "exec,nochain", "-D"])
        .arg(&log)
        .status()
        .expect("qemu-system-arm");
    assert!(st.success(), "QEMU run of {} failed", elf.display());
    let (a0, n0) = symbol(elf, "profile_start");
    let (a1, n1) = symbol(elf, "profile_stop");
    let text = std::fs::read_to_string(&log).expect("QEMU's log");
    std::fs::remove_file(&log).ok();
    let mut pcs = Vec::new();
    let mut on = false;
    for l in text.lines() {
        // "Trace 0: 0x... [flags/pc/...]"
        let Some(pc) = l.split('[').nth(1).and_then(|s| s.split('/').nth(1)).and_then(|h| u64::from_str_radix(h, 16).ok()) else {
            continue;
        };
        if (a0..a0 + n0).contains(&pc) {
            on = true;
        } else if (a1..a1 + n1).contains(&pc) {
            break;
        } else if on {
            pcs.push(pc);
        }
    }
    assert!(on && !pcs.is_empty(), "no instructions between the markers");
    pcs
}

/// Each address's innermost function in model/src (its name without generic arguments), from
/// `addr2line -i -f -C`; "outside the model" for the rest (core's, compiler_builtins').
fn functions(elf: &Path, pcs: &[u64]) -> HashMap<u64, String> {
    let mut uniq: Vec<u64> = pcs.to_vec();
    uniq.sort_unstable();
    uniq.dedup();
    let out = Command::new("addr2line")
        .arg("-e")
        .arg(elf)
        .args(["-i", "-f", "-C", "-a"])
        .args(uniq.iter().map(|p| format!("{p:#x}")))
        .output()
        .expect("addr2line (binutils)");
    let text = String::from_utf8_lossy(&out.stdout);
    let mut map = HashMap::new();
    let mut cur: Option<u64> = None;
    let mut frames: Vec<String> = Vec::new();
    let mut flush = |cur: Option<u64>, frames: &mut Vec<String>| {
        if let Some(pc) = cur {
            // frames alternate function, file:line, innermost first
            let name = frames
                .chunks(2)
                .find(|c| c.len() == 2 && c[1].contains("/model/src/"))
                .map(|c| strip_generics(&c[0]))
                .unwrap_or_else(|| "outside the model (core, compiler_builtins)".to_string());
            map.insert(pc, name);
        }
        frames.clear();
    };
    for l in text.lines() {
        if let Some(h) = l.strip_prefix("0x") {
            flush(cur, &mut frames);
            cur = u64::from_str_radix(h, 16).ok();
        } else {
            frames.push(l.to_string());
        }
    }
    flush(cur, &mut frames);
    map
}

/// `a::<impl b<R>>::c<T>` without the angle brackets' contents, and without the crate prefix.
fn strip_generics(s: &str) -> String {
    let mut out = String::new();
    let mut depth = 0;
    for ch in s.chars() {
        match ch {
            '<' => depth += 1,
            '>' => depth -= 1,
            _ if depth == 0 => out.push(ch),
            _ => {}
        }
    }
    out.trim_start_matches("finger_model::").replace("::::", "::").replace("{{closure}}", "closure")
}

fn part(name: &str) -> &'static str {
    PARTS.iter().find(|(_, frags)| frags.iter().any(|f| name.contains(f))).map(|p| p.0).unwrap_or("the rest")
}

fn main() {
    let mut doc =
        host_tests::report::generated_header("cargo run --release --example inverse_profile", "# Where the tabled inverse's instructions go (Cortex-M4F)");
    writeln!(
        doc,
        "One `solve_pose_tabled_into` in f32 with the firmware's model features (fast-trig), the \
         bench image `bench/src/bin/table.rs` built with its `profile` feature: the calibrated \
         model (m = 8; the last two cases the paper's m = 1 finger, `m1-paper`), the joint angles of its forward solve at 1 N with the voltages 2, 6 and \
         9 kV (three different joints) or 5 kV on all three (identical joints), inverted at 1 N \
         (tension given) or with the midpoint rule (tension free). QEMU netduinoplus2 with \
         `-icount shift=0 -singlestep -d exec,nochain` logs every instruction executed; each one \
         between the markers is counted against the innermost model function whose code it is \
         (`addr2line -i`: inlined functions count as themselves). A count here can differ from \
         docs/performance.md's by the markers' calls and the scene's tension.\n"
    )
    .unwrap();
    for case in CASES {
        let elf = build(case);
        let pcs = trace(&elf);
        let names = functions(&elf, &pcs);
        let mut by_fn: BTreeMap<&str, usize> = BTreeMap::new();
        for pc in &pcs {
            *by_fn.entry(names[pc].as_str()).or_default() += 1;
        }
        let mut by_part: BTreeMap<&str, usize> = BTreeMap::new();
        for (f, n) in &by_fn {
            *by_part.entry(part(f)).or_default() += n;
        }
        writeln!(doc, "## {}: {} instructions\n", case.name, pcs.len()).unwrap();
        writeln!(doc, "| part | instructions | share |\n| --- | ---: | ---: |").unwrap();
        let order = PARTS.iter().map(|p| p.0).chain(["the rest"]);
        for p in order {
            let n = by_part.get(p).copied().unwrap_or(0);
            writeln!(doc, "| {p} | {n} | {:.0} % |", 100.0 * n as f64 / pcs.len() as f64).unwrap();
        }
        let mut fns: Vec<(&str, usize)> = by_fn.into_iter().collect();
        fns.sort_by(|a, b| b.1.cmp(&a.1).then(a.0.cmp(b.0)));
        writeln!(doc, "\n| function (innermost in model/src) | part | instructions |\n| --- | --- | ---: |").unwrap();
        for (f, n) in fns.iter().filter(|(_, n)| *n >= 20) {
            writeln!(doc, "| `{f}` | {} | {n} |", part(f)).unwrap();
        }
        let small: usize = fns.iter().filter(|(_, n)| *n < 20).map(|(_, n)| n).sum();
        writeln!(doc, "| (functions under 20 each) | | {small} |\n").unwrap();
        println!("{}: {} instructions", case.name, pcs.len());
    }
    let path = Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/inverse-profile.md");
    std::fs::write(&path, doc).expect("write docs/inverse-profile.md");
    println!("wrote {}", path.display());
}
