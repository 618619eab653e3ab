//! What Miri runs (`cargo +nightly miri test --test miri_paths`, in scripts/fuzz-soak): the
//! host paths through unsafe code. The model and the firmware library have no unsafe code
//! on the host (the model's one exception, the M4F's `vsqrt`, is compiled for the chip only;
//! the chip code is not in the library); the unsafe they reach is heapless's: the RX ring
//! (`Deque`) wrapping around, overruns and too-long lines, the line and reply buffers
//! (`Vec`, `String`) of every console command. Small inputs: Miri interprets, which is slow.
use finger_fuzz::{console, model, rx};

#[test]
fn rx_ring_wraps_overruns_and_too_long_lines() {
    let mut data = Vec::new();
    // fill the ring past its end several times, taking records in between (wrap-around)
    for round in 0..6 {
        for i in 0..40 {
            data.extend_from_slice(format!("line {round} {i} {}\n", "x".repeat(i * 3)).as_bytes());
        }
        data.push(rx::POP);
    }
    data.extend_from_slice(b"solve 1 ");
    data.push(rx::OVERRUN);
    data.extend_from_slice(b"2 3 4\n");
    data.extend_from_slice(&[b'a'; 300]);
    data.extend_from_slice(b"\nstop\n");
    data.push(rx::POP);
    rx::check(&data);
}

#[test]
fn console_commands_on_the_simulated_board() {
    // the commands that need no solve (a solve under Miri takes minutes): lines, replies,
    // parameters, arm, HV setpoints and their slew, stop, refusals, a too-long line
    let t = console::TICK;
    let mut data = b"help\nversion\nparam\nparam slew 5000\narm\nvolt all 300\n".to_vec();
    data.extend_from_slice(&[t, 20]);
    data.extend_from_slice(b"STOP\nbogus 1 2\nvolt 1 nan\n");
    data.extend_from_slice(&[b'z'; 200]);
    data.extend_from_slice(b"\n");
    console::check(&data);
}

#[test]
fn model_forward() {
    // the paper's parameters (m = 1, rigid links), one joint: fmax and a forward solve
    model::check(&[1, 1, 0, 0, 80, 100, 100]);
}
