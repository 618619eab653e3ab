//! docs/performance.md's "`contact` on the Cortex-M4F" section alone (perf-report's contact
//! image): `cargo run --release --example contact_section` in host-tests/.
fn main() {
    print!("{}", host_tests::perf::contact_cost_section());
}
