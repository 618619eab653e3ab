//! Regenerates docs/firmware.md's shaped-actuation figures (between the `hv-settle` markers):
//! the control core on the simulated board (`host_tests::hv`), a step from rest on one channel
//! to a fraction of the board's hold ceiling, plain and shaped, at the default slew; the time
//! until the predicted thickness stays within 1 % of the target's equilibrium thickness, the
//! thinnest it got, and the highest voltage the shaped drive used.
//!   cd host-tests && cargo run --release --example hv_settle
use finger_fw::board::board_law;
use finger_fw::control::Control;
use finger_fw::sim::SimBoard;
use finger_fw::FwParams;
use finger_model::material::equilibrium_ratio;
use host_tests::hv::{settling_s, step_response};

fn main() {
    let hold = Control::new(SimBoard::default(), 2000, 2000.0).hold_ceiling_v();
    let law = board_law().unwrap();
    let slew = FwParams::default().slew;
    let secs = 600;
    let fmt = |t: Option<f64>| t.map(|t| format!("{t:.2} s")).unwrap_or_else(|| format!("> {secs} s"));
    let mut s = String::new();
    s.push_str("<!-- hv-settle:begin (cd host-tests && cargo run --release --example hv_settle) -->\n");
    s.push_str(&format!(
        "A step from rest on one channel, slewed at {slew} V/s, the board's card and hold ceiling ({hold:.0} V); settling: until the\n\
         predicted thickness stays within 1 % of the target's equilibrium thickness (a run of {secs} s).\n\n"
    ));
    s.push_str("| target | s at equilibrium | plain: settles in | shaped: settles in | shaped: thinnest s | shaped: highest V |\n");
    s.push_str("| --- | --- | --- | --- | --- | --- |\n");
    for frac in [0.5f32, 0.75, 1.0] {
        let v = frac * hold;
        let s_t = equilibrium_ratio(&law, v).unwrap();
        let plain = step_response(v, false, slew, secs);
        let shaped = step_response(v, true, slew, secs);
        let thinnest = shaped.iter().map(|x| x.0).fold(1.0f32, f32::min);
        let vtop = shaped.iter().map(|x| x.1).fold(0.0f32, f32::max);
        s.push_str(&format!(
            "| {v:.0} V ({:.0} % of the hold ceiling) | {s_t:.4} | {} | {} | {thinnest:.4} | {vtop:.0} V |\n",
            frac * 100.0,
            fmt(settling_s(&plain, s_t)),
            fmt(settling_s(&shaped, s_t))
        ));
    }
    s.push_str("<!-- hv-settle:end -->\n");
    host_tests::report::write_section("docs/firmware.md", "hv-settle", &s);
    print!("{s}");
}
