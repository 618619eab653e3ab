//! Instructions per inverse solve on the Cortex-M4F: builds the bench image
//! `bench/src/bin/inverse.rs` in five variants (libm trig with the inverse's m = 1 fast path;
//! fast-trig with it; libm and fast-trig without it; fast-trig without it and with the branch
//! table, as the firmware builds and uses the model), runs each in QEMU
//! netduinoplus2 with `-icount shift=0`, and writes docs/inverse-cost.md.
//!
//! `cd host-tests && cargo run --release --example inverse_cost`

use host_tests::perf;
use std::fmt::Write as _;

fn main() {
    let mut doc = host_tests::report::generated_header("cargo run --release --example inverse_cost", "# Instructions per inverse solve on the Cortex-M4F");
    writeln!(
        doc,
        "One `inverse::solve_pose` in f32 (joint angles, and optionally a tension, to the tension and the \
         three voltages), counted in QEMU netduinoplus2 with `-icount shift=0` (SysTick calibrated on a \
         loop of known length). `m1-rigid` is the paper's model (m = 1, E_b, rigid links), \
         `m8-plate-flex` the default model (m = 8, plate modulus, flexible links). Without a tension the \
         inverse also finds the feasible tension interval (both ends) and takes its midpoint. The last \
         column solves with the finger's branch table (`solve_pose_tabled`, model inverse/table.rs and \
         general.rs `solve_tabled`: step 1's tension ranges read off the table and only the ends the answer \
         rests on confirmed, one march each: without a tension the interval's bounds, with one none; step 4 \
         one compliance evaluation and one march from the table's point on the level curve; a refusal is \
         decided and reported by the untabled steps, which confirm the bounding ends; the table built once \
         per parameter set, its cost below the table), as the firmware does (a solution returned by value; \
         docs/performance.md has `solve_pose_tabled_into`, written in place). The images are built with opt-level 3 (the \
         firmware's own image with opt-level z). The target: at most 20,000 instructions on the firmware's \
         path (the last column). The untabled solves end with the forward solve from rest at the answer \
         (docs/inverse.md \"Reached from rest\": an answer the finger does not reach is refused), which \
         the tabled path does not need: 13,000 to 19,000 (m = 1) and 20,000 to 39,000 (m = 8) of their counts.\n"
    )
    .unwrap();
    doc.push_str(&perf::inverse_cost_table());
    let path = std::path::Path::new(env!("CARGO_MANIFEST_DIR")).join("../docs/inverse-cost.md");
    std::fs::write(&path, doc).unwrap();
    println!("wrote {}", path.display());
}
