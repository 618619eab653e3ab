//! The bench image path, once: build the quick bench image (one scene, converged solver, f32)
//! for the Cortex-M4F, run it in QEMU with -icount, and check what it reports against the
//! host's f64 reference. The full report (`cargo run --release --bin perf-report`) is not part
//! of the test suite; this keeps CI noticing when its path breaks.

use host_tests::perf::{self, scenes::SCENES, QUICK};

#[test]
fn quick_bench_image_runs_in_qemu_and_matches_the_host_reference() {
    let elf = perf::build("finger-bench", QUICK.triple, QUICK.features, QUICK.name).unwrap();
    let out = perf::run_qemu(&elf, QUICK.machine, QUICK.shift).unwrap();
    let recs = perf::parse(&QUICK, &out).unwrap();
    assert_eq!(recs.len(), 1, "one scene, one method:\n{out}");
    let r = &recs[0];
    assert_eq!((r.scene.as_str(), r.method.as_str()), ("bare-1.0N", "conv"));
    let scene = SCENES.iter().find(|s| s.name == r.scene).unwrap();
    let reference = perf::reference(scene).unwrap();
    let (tip, angles, _) = r.result.clone().unwrap();
    let (tip_err, ang_err) = perf::errors(tip, angles, &reference);
    // f32 on the target: within f32 rounding of the f64 reference (tip ~80 mm from the base)
    assert!(tip_err < 1e-3, "tip error {tip_err} mm");
    assert!(ang_err < 1e-3, "angle error {ang_err} deg");
    assert!(r.instr > 0.0 && r.instr.is_finite(), "instruction count {}", r.instr);
}

#[test]
fn elf_sizes_of_the_quick_image_are_plausible() {
    // its own copy of the image: the other test runs QEMU on `QUICK.name` concurrently
    let elf = perf::build("finger-bench", QUICK.triple, QUICK.features, "m4f-quick-sizes").unwrap();
    let (flash, ram) = perf::elf_sizes(&elf).unwrap();
    // it holds the model, libm and the formatter; RAM holds at least the SysTick counter
    assert!(flash > 4096 && flash < 1024 * 1024, "flash {flash}");
    assert!(ram > 0 && ram < 128 * 1024, "ram {ram}");
    assert!(perf::elf_sizes(std::path::Path::new(file!())).is_err(), "a non-ELF is refused");
}
