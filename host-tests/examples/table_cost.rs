//! The branch-table path on the Cortex-M4F: prints the section perf-report puts in
//! docs/performance.md (`host_tests::perf::table_cost_section`), without the rest of the report.
//!
//! `cd host-tests && cargo run --example table_cost`

fn main() {
    print!("{}", host_tests::perf::table_cost_section());
}
