"""The board from Python: Board.sim() and Board.qemu() pass the console checks the Rust client
passes (tools/finger/tests/client.rs), refusals come back typed, a mute board raises a
time-out, and the context manager leaves HV at 0 when its block raises (and on Ctrl-C). Voltages
come from the board's own `limits`, not constants."""

import os
import signal
import subprocess
import sys
import textwrap
import time

import numpy as np
import pytest

import softfinger as sf


def same_session(board: sf.Board) -> None:
    """The session of client.rs's `same_session`, on any board."""
    assert board.fields("version")["name"] == "finger-fw"
    st = board.status()
    assert not st.armed and st.fault == "none"
    lim = board.limits()
    assert len(lim.vmax_V) == 3 and all(0 < v < lim.vpullin_V for v in lim.vmax_V)
    assert board.command("solve 0.5 0 1000 2000").startswith("ok joints=")
    # every reply typed: solve, pose (disarmed: nothing moves), force
    s = board.solve(0.5, [0, 1000, 2000])
    assert isinstance(s, sf.BoardSolution) and len(s.joints_deg) == 3 and len(s.stiffness) == 3
    p = board.pose(5, 5, 5)
    assert isinstance(p, sf.Pose) and p.force_N > 0 and len(p.volts_V) == 3 and p.range_N[0] <= p.force_N <= p.range_N[1]
    assert p.moved is False and board.status().force_N == 0.0
    board.arm()
    fr = board.force(0.2)
    assert isinstance(fr, sf.Force) and fr.force_N == 0.2 and fr.cable_mm > 0
    v = 0.05 * min(lim.vmax_V)  # below every channel's ceiling, whatever the card
    assert board.volt("all", v) == (v, v, v)
    board.wait(0.3)
    assert board.status().volts_V == pytest.approx((v, v, v), abs=0.05)
    # a refusal is typed, with its code
    board.disarm()
    with pytest.raises(sf.BoardError) as e:
        board.volt(1, v)
    assert e.value.code == "not-armed"
    with pytest.raises(sf.BoardError) as e:
        board.command("frobnicate")
    assert e.value.code == "unknown"
    with pytest.raises(sf.BoardError) as e:
        board.command("solve 0.5 0 0 nan")
    assert e.value.code == "bad-number"
    # the ceiling refuses at the ceiling itself
    board.arm()
    with pytest.raises(sf.BoardError) as e:
        board.volt(2, lim.vmax_V[1])
    assert e.value.code == "limit"


def test_sim_answers_the_console_contract(sim_program):
    with sf.Board.sim(sim_program) as b:
        same_session(b)
    assert b.final_status is not None and not b.final_status.armed


def test_qemu_answers_the_same_session(fw_elf):
    with sf.Board.qemu(fw_elf) as b:
        assert b.banner.startswith("# finger-fw")
        same_session(b)
    assert b.final_status is not None and b.final_status.volts_V == (0.0, 0.0, 0.0)


def test_late_replies_and_a_flushing_stop_keep_replies_matched(fw_elf):
    """On the emulator image, whose command side takes time: a command that timed out still
    answers later, a line queued behind it is dropped by the `stop` (`err stopped`), and `ok
    stopped` comes before both (docs/console.md "Lines"); every later command still gets its
    own reply."""
    with sf.Board.qemu(fw_elf) as b:
        with pytest.raises(sf.BoardTimeout):
            b.command("limits", timeout_s=0.001)  # its fmax search: milliseconds of QEMU time
        try:
            b.command("arm", timeout_s=0.001)  # queued behind limits
        except sf.BoardTimeout:
            pass
        b.stop()
        st = b.status()
        assert not st.armed and st.volts_V == (0.0, 0.0, 0.0)
        assert b.fields("version")["name"] == "finger-fw"
        assert b.limits().vmax_V[0] > 0
    assert b.final_status is not None and not b.final_status.armed


def test_board_solve_equals_the_python_model_to_its_printed_digits(sim_program):
    """The board's f32 `solve` against `Finger()`, the f64 model of the board's finger: its
    film's card is the board's (`material`), its calibration the board's (`cal`), its ceiling
    the board's (`limits`); each printed value is the model's rounded to the printed digits,
    within one unit of the last (f32)."""
    with sf.Board.sim(sim_program) as b:
        card = b.command("material").split("card=")[1].split()[0]
        cal = [float(x) for x in b.command("cal").split("cal=")[1].split(",")]
        f = sf.Finger()
        lim = b.limits()
        assert f.card == card and f.calibration == pytest.approx(cal, abs=5e-7), (f, cal)
        assert f.ceiling() == pytest.approx(min(lim.vmax_V), abs=0.05), (f, lim)
        for word in ("card=", "calibration=", "ceiling="):
            assert word in repr(f), f
        # the board's ceiling is the model's too: at it, both refuse
        with pytest.raises(sf.VoltageCeilingError):
            f.solve(1.0, [0, 0, min(lim.vmax_V)])
        with pytest.raises(sf.BoardError) as e:
            b.solve(1.0, [0, 0, min(lim.vmax_V)])
        assert e.value.code == "limit"
        # and a negative pose angle is refused in the same words
        with pytest.raises(sf.BoardError) as e:
            b.pose(-10, 0, 0)
        with pytest.raises(sf.UnreachableError) as m:
            f.pose([-10, 0, 0], degrees=True)
        assert str(m.value) == e.value.message and m.value.code == e.value.code
        top = 0.9 * min(lim.vmax_V)
        for P, volts in [(0.2, [0, 0, 0]), (0.5, [0, 0.3 * top, 0.6 * top]), (1.0, [top, top / 2, 0]), (2.0, [top] * 3)]:
            r = b.solve(P, volts)
            s = f.solve(P, volts)
            line = b.command("solve " + " ".join(repr(float(x)) for x in [P, *volts]))
            text = dict(kv.split("=", 1) for kv in line.split()[1:])
            model = {
                "joints": s.joints_deg,
                "tip": [s.tip[0], s.tip[1], np.degrees(s.tip[2])],
                "cable": [s.cable_mm],
                "thick": s.thickness_mm,
            }
            for key, want in model.items():
                for printed, value in zip(text[key].split(","), want):
                    decimals = len(printed.split(".")[1]) if "." in printed else 0
                    unit = 10.0 ** -decimals
                    assert abs(float(printed) - value) <= unit, (key, printed, value, line)
            assert r.joints_deg == tuple(float(x) for x in text["joints"].split(","))
            assert isinstance(r, sf.BoardSolution) and isinstance(r.iters, int)


def test_a_mute_board_times_out_and_a_closed_one_says_so(tmp_path):
    mute = tmp_path / "mute-board"
    mute.write_text("#!/bin/sh\nexec sleep 30\n")
    mute.chmod(0o755)
    b = sf.Board.sim(mute, timeout_s=0.5)
    t0 = time.monotonic()
    with pytest.raises(sf.BoardTimeout):
        b.status()
    assert time.monotonic() - t0 < 5.0
    b.close()  # its stop times out too; close does not hang
    assert time.monotonic() - t0 < 10.0 and b.final_status is None
    gone = sf.Board.sim("/bin/true", timeout_s=2.0)
    with pytest.raises(sf.BoardLinkError):
        gone.status()
    gone.close()
    with pytest.raises(sf.BoardLinkError):
        sf.Board(port="/nonexistent/tty")


def test_a_closed_board_leaves_no_reader_on_its_freed_pipe(sim_program, monkeypatch):
    """The root of the intermittent BoardTimeout (docs/reliability.md): `close()` freed the pipe
    while the board's reader thread, starved on a loaded machine, had yet to read again; the next
    board's pipe reused the descriptor and the old reader took that board's replies. Here every
    read is late: each next board still gets its own replies, and no reader outlives its board."""
    real_read = os.read

    def late(fd, n):
        time.sleep(0.05)
        return real_read(fd, n)

    monkeypatch.setattr(os, "read", late)
    for _ in range(3):
        a = sf.Board.sim(sim_program)
        a.command("version")
        a.close(stop=False)
        assert not a._link._thread.is_alive()
        with sf.Board.sim(sim_program) as b:
            assert b.limits().vmax_V[0] > 0


def test_the_context_manager_leaves_hv_at_0_when_the_block_raises(sim_program):
    board = sf.Board.sim(sim_program)
    with pytest.raises(RuntimeError):
        with board as b:
            lim = b.limits()
            b.arm()
            b.volt("all", 0.5 * min(lim.vmax_V))
            b.wait(1.0)
            assert min(b.status().volts_V) > 0.0
            raise RuntimeError("the experiment failed")
    st = board.final_status
    assert st is not None and not st.armed and st.volts_V == (0.0, 0.0, 0.0)


def test_ctrl_c_sends_stop(sim_program, tmp_path):
    """A real SIGINT to a script inside `with Board.sim()`: the board reports HV at 0 after."""
    script = tmp_path / "drive.py"
    script.write_text(textwrap.dedent(f"""
        import time, softfinger as sf
        board = sf.Board.sim({str(sim_program)!r})
        try:
            with board as b:
                b.arm()
                b.volt("all", 0.5 * min(b.limits().vmax_V))
                b.wait(1.0)
                print("armed", b.status().volts_V, flush=True)
                time.sleep(60)
        except KeyboardInterrupt:
            st = board.final_status
            print("final", st.armed, st.volts_V, flush=True)
    """))
    # SIGINT as a terminal's Ctrl-C delivers it, even where this runs with SIGINT ignored (a
    # background job of a script): the child would inherit that and never see the signal
    p = subprocess.Popen([sys.executable, str(script)], stdout=subprocess.PIPE, text=True,
                         preexec_fn=lambda: signal.signal(signal.SIGINT, signal.SIG_DFL))
    first = p.stdout.readline()
    assert first.startswith("armed"), first
    p.send_signal(signal.SIGINT)
    out, _ = p.communicate(timeout=120)  # a hang, not a slow machine
    assert out.strip() == "final False (0.0, 0.0, 0.0)", out


def test_status_carries_the_hv_read_back(sim_program):
    """finger-sim runs against the HV plant: status' measured voltage follows the command and
    the thickness sensed from the stacks' capacitance follows the model's."""
    with sf.Board.sim(sim_program) as b:
        assert b.status().vmeas_V is not None
        b.arm()
        v = 0.5 * min(b.limits().vmax_V)
        b.volt("all", v)
        b.wait(3)
        st = b.status()
        # the hold ripple takes up to 100 V off the measured voltage, never adds
        assert all(v - 110 <= m <= v + 10 for m in st.vmeas_V), st.vmeas_V
        assert all(abs(i) < 1.0 for i in st.imeas_uA), st.imeas_uA
        assert st.thick_meas_mm == pytest.approx(st.thick_mm, rel=0.02)


def test_contact_has_one_sign_on_the_board_and_in_python(sim_program):
    """`force_on_tip` (the stop's force on the tip) is Python's `force_on_tip_N`; the board's
    older `fx`, `fy` are its opposite (the tip's force on the stop)."""
    with sf.Board.sim(sim_program) as b:
        r = b.fields("contact 1 1.5")
    c = sf.Finger().contact(1.0, 1.5, [0, 0, 0])
    assert np.allclose(r["force_on_tip"], c.force_on_tip_N, atol=2e-4), (r, c)
    assert np.allclose(c.force_on_tip_N, c.force_N)
    assert np.allclose((r["fx"], r["fy"]), -c.force_on_tip_N, atol=2e-4), (r, c)
    assert "force_on_tip_N=" in repr(c)


def test_the_final_status_reads_the_stacks_discharged(sim_program):
    """`stop` then the board's own time: the final status measures ~0 V on every stack, as a
    real board does a moment after a stop (was about 2.9 kV: finger-sim's time stood still)."""
    with sf.Board.sim(sim_program) as b:
        b.arm()
        b.volt("all", 3000)
        b.wait(2.0)
        assert all(v > 2500 for v in b.status().vmeas_V)
    st = b.final_status
    assert st is not None and not st.armed and st.volts_V == (0.0, 0.0, 0.0)
    assert all(abs(v) < 50 for v in st.vmeas_V), st
