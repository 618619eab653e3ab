//! Instructions per fmax (`Finger::fmax`, `BranchTable::fmax`) on the Cortex-M4F: builds the bench image
//! `bench/src/bin/fmax.rs` with the firmware's trig (fast-trig), runs it in QEMU netduinoplus2
//! with `-icount shift=0`, and writes docs/fmax-cost.md.
//!
//! `cd host-tests && cargo run --example fmax_cost`

use host_tests::perf::{build, read_bench, run_qemu, M4F};
use std::fmt::Write as _;

fn main() {
    let elf = build("fmax", M4F, "de,fast-trig", "fmax-de-fast-trig").unwrap_or_else(|e| panic!("{e}"));
    let out = run_qemu(&elf, "netduinoplus2", 0).unwrap_or_else(|e| panic!("{e}"));
    let mut doc = host_tests::report::generated_header("cargo run --example fmax_cost", "# Instructions per fmax on the Cortex-M4F");
    writeln!(
        doc,
        "One fmax in f32 (the end of the equilibrium branch at the given voltages: identical joints \
         solved once, a march up the branch, then the bracketed boundary search, model \
         finger/branch_end.rs), counted in QEMU netduinoplus2 with `-icount shift=0` (SysTick calibrated \
         on a loop of known length), image built with opt-level 3 and fast-trig (the firmware's trig). \
         *full*: `Finger::fmax`, the march from the straight joint in doubling steps; *table*: \
         `BranchTable::fmax` (what the firmware runs), the march started at the branch table's last \
         sample (model inverse/table.rs), the same search after it. The table is built once per \
         parameter set and shared with the forward and inverse solves; its cost is listed below the \
         table. Voltages as fractions of the ceiling (1 - 1e-4 of it at `top`; `mixed` is 0, 0.5, 1). \
         The target: at most 500,000 instructions.\n"
    )
    .unwrap();
    writeln!(doc, "| case | full: instructions | full: fmax | table: instructions | table: fmax | ends at (table) |\n| --- | --- | --- | --- | --- | --- |")
        .unwrap();
    let bench = read_bench(&out).unwrap_or_else(|e| panic!("{e}"));
    let instr = |t: &str| bench.instructions(t.parse().unwrap()).round();
    let (mut worst_full, mut worst_table) = (0.0f64, 0.0f64);
    let mut builds = Vec::new();
    let mut full: Option<(String, f64, String)> = None;
    for f in &bench.lines {
        match f[0] {
            "B" => builds.push(format!("{} {:.0}", f[1], instr(f[2]))),
            "F" => {
                let n = instr(f[4]);
                let what = if f[3] == "ok" { format!("{:.4} N", f[5].parse::<f64>().unwrap()) } else { format!("err {}", f[5]) };
                if f[2] == "full" {
                    worst_full = worst_full.max(n);
                    full = Some((f[1].to_string(), n, what));
                } else {
                    worst_table = worst_table.max(n);
                    let end = if f[3] == "ok" { format!("joint {}, {}", f[6], f[7]) } else { String::new() };
                    let (case, fi, fw) = full.take().filter(|c| c.0 == f[1]).unwrap_or((f[1].to_string(), f64::NAN, "-".into()));
                    writeln!(doc, "| {case} | {fi:.0} | {fw} | {n:.0} | {what} | {end} |").unwrap();
                }
            }
            _ => {}
        }
    }
    writeln!(doc, "\nAt most {worst_full:.0} instructions (full), {worst_table:.0} from the table (the firmware).").unwrap();
    writeln!(doc, "\nBuilding the branch table (`inverse::BranchTable::new`, once per parameter set), instructions: {}.", builds.join("; ")).unwrap();
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/fmax-cost.md");
    std::fs::write(&path, &doc).unwrap();
    print!("{doc}");
    println!("wrote {}", path.display());
}
