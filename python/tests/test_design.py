"""The design study (softfinger.design, docs/design.md): a small study finds a design that
meets every constraint, a design the model refuses is infeasible and not a crash, a killed
study resumes with its trials, the model pickles, and a design file builds a board whose
ceiling is the design's."""

import os
import pickle
import shutil
import signal
import subprocess
import sys
import time

import numpy as np
import pytest

import softfinger as sf
from softfinger.design import CONSTRAINTS, Design, evaluate, run_study, storage_of
from softfinger.design.evaluate import HORIZONTAL
from softfinger.design.study import feasible_trials, study_name

from conftest import ROOT, cargo, host_target_dir


def test_a_small_study_finds_a_feasible_design(tmp_path):
    st = run_study("Elastosil-2030", 48, storage_of(tmp_path / "s.journal"), batch=16, progress=False)
    assert len(st.trials) == 48
    ok = feasible_trials(st)
    assert ok, "no feasible design in 48 trials"
    best = max(ok, key=lambda t: t.values[0])
    # the stored constraints are the sampler's (Trial.set_constraint) and all hold
    cons = [best.system_attrs[f"constraints:{c}"] for c in CONSTRAINTS]
    assert all(c <= 0 for c in cons), cons
    # the design evaluated again: feasible, the same ratio, a real change of stiffness
    d = Design(card="Elastosil-2030", margin=0.9, **{k: (int(v) if k == "layers" else v) for k, v in best.params.items()})
    # (the study's orientation: held horizontally under its weight)
    ev = evaluate("Elastosil-2030", [d], grav=HORIZONTAL[0], grav_dir=HORIZONTAL[1])
    assert ev.feasible[0] and ev.objectives[0, 0] == pytest.approx(best.values[0], rel=1e-12)
    assert ev.objectives[0, 0] > 1.001
    r = ev.row(0)
    assert r["volts_top_V"] < r["ceiling_V"] and r["s_min"] > 2 / 3 and r["fmax_N"] >= 2.0


def test_a_refused_design_is_infeasible_not_a_crash():
    good = Design(card="VHB-4905")
    designs = [Design(card="VHB-4905", t_min=12.0), good, Design(card="VHB-4905", t_min=0.5, e_b=12.0, a=10.0, w=10.0, layers=12)]
    ev = evaluate("VHB-4905", designs)
    # the model's own refusals, by stage and kind: t_min >= b, and the grip's contact at a limit point
    assert ev.error[0] == "params:Param" and ev.error[2].startswith("grip:")
    assert not ev.feasible[0] and not ev.feasible[2] and ev.feasible[1]
    assert ev.constraints[0, CONSTRAINTS.index("refused")] == 1.0
    assert np.all(np.isfinite(ev.constraints)) and np.all(np.isfinite(ev.objectives))
    # the refused rows cost the good one nothing: the same numbers as alone
    alone = evaluate("VHB-4905", [good])
    assert ev.objectives[1].tolist() == alone.objectives[0].tolist()
    # the same refusal raises its typed exception from the plain model
    with pytest.raises(sf.InputError):
        designs[0].finger()


def test_a_killed_study_resumes_with_its_trials(tmp_path):
    journal = tmp_path / "s.journal"
    code = (
        "from softfinger.design import run_study, storage_of\n"
        f"run_study('VHB-4905', 100000, storage_of({str(journal)!r}), batch=16, progress=False)\n"
    )
    proc = subprocess.Popen([sys.executable, "-c", code], cwd=tmp_path)
    import optuna

    def stored():
        if not journal.exists():
            return []
        try:
            return optuna.load_study(study_name=study_name("VHB-4905", HORIZONTAL), storage=storage_of(journal)).get_trials(deepcopy=False)
        except KeyError:
            return []

    deadline = time.monotonic() + 120
    while len(stored()) < 48 and time.monotonic() < deadline and proc.poll() is None:
        time.sleep(0.2)
    proc.send_signal(signal.SIGKILL)
    proc.wait()
    before = stored()
    assert len(before) >= 48, "the study stored too few trials to test"
    assert all(t.state == optuna.trial.TrialState.COMPLETE for t in before)
    n = len(before)
    st = run_study("VHB-4905", n + 16, storage_of(journal), batch=16, progress=False)
    after = st.get_trials(deepcopy=False)
    assert len(after) == n + 16
    assert [t.params for t in after[:n]] == [t.params for t in before]
    assert [t.values for t in after[:n]] == [t.values for t in before]


def test_the_model_and_a_design_pickle():
    for f in (sf.Finger(preset="default", calibration=None, card="Elastosil-2030", t_min=0.8, layers=12, z0=0.1), sf.Finger(preset="paper"), sf.Finger()):
        g = pickle.loads(pickle.dumps(f))
        assert g.params == f.params and g.calibration == f.calibration and g.card == f.card
        a, b = f.solve(0.5, [0, 1000, 2000]), g.solve(0.5, [0, 1000, 2000])
        assert a.joints_rad.tolist() == b.joints_rad.tolist() and a.stiffness.tolist() == b.stiffness.tolist()
        assert g.ceiling() == f.ceiling()
    d = Design(card="Elastosil-2030", layers=12, z0=0.1)
    assert pickle.loads(pickle.dumps(d)) == d
    assert Design.from_toml(d.to_toml("a comment")) == d
    # with its FE calibration: the 8 factors round-trip, and the model is the calibrated one
    c = d.replace(cal=(1.36, 1.66, 1.05, 1.06, 0.82, 0.04, 1.4, -0.12))
    assert Design.from_toml(c.to_toml()) == c and pickle.loads(pickle.dumps(c)) == c
    assert c.finger().calibration == list(c.cal) and d.finger().calibration == [1, 1, 1, 1, 1, 0, 1, 0]
    for bad in ("cal = [1.0, 2.0]", "cal = \"none\"", "cal = [1, 1, 1, 1, 1, 0, 1, nan]"):
        with pytest.raises(ValueError, match="cal"):
            Design.from_toml(d.to_toml() + bad + "\n")
    with pytest.raises(ValueError):
        Design.from_toml(d.to_toml() + "t_mni = 1.0\n")
    # a path, as a Path or as the text of one, reads the file (was a TOMLDecodeError)
    path = ROOT / "designs" / "VHB-4905.toml"
    assert Design.from_toml(path) == Design.load(path) == Design.from_toml(str(path))
    with pytest.raises(FileNotFoundError) as e:
        Design.from_toml("designs/no-such.toml")
    assert "Design.load" in str(e.value)
    with pytest.raises(ValueError) as e:
        Design.from_toml("not = toml = text")
    assert "TOML text or a path" in str(e.value)


def test_a_design_file_carries_the_orientation_of_the_board_it_builds():
    d = Design(card="VHB-4905")
    # the board's orientation by default: standard gravity, hanging straight down
    assert (d.grav, d.grav_dir) == (sf.Finger().params["grav"], sf.Finger().params["grav_dir"]) == (9.81, 0.0)
    text = d.to_toml()
    assert "grav = 9.81\n" in text and "grav_dir = 0.0\n" in text
    h = d.replace(grav_dir=90.0)
    assert Design.from_toml(h.to_toml()) == h
    f = h.finger()
    assert (f.params["grav"], f.params["grav_dir"]) == (9.81, 90.0)
    # a file from before gravity (no orientation keys) builds the board's
    old = "\n".join(l for l in text.splitlines() if not l.startswith("grav")) + "\n"
    assert Design.from_toml(old) == d
    for bad in ("grav = 25.0", "grav_dir = 200.0", "grav_dir = \"down\""):
        key = bad.split(" ")[0]
        with pytest.raises(ValueError, match=key):
            Design.from_toml(old + bad + "\n")
    # the study's inputs stay the design variables; its evaluation takes an orientation
    assert "grav" not in d.params() and d.orientation() == {"grav": 9.81, "grav_dir": 0.0}
    with pytest.raises(sf.InputError) as e:
        evaluate("VHB-4905", [d], grip=False, grav_dir=200.0)
    assert e.value.fields["name"] == "grav_dir"
    assert evaluate("VHB-4905", [d], grip=False, grav=9.81, grav_dir=90.0).feasible.shape == (1,)


def sim_lines(program, lines):
    out = subprocess.run([str(program)], input="".join(l + "\n" for l in lines), capture_output=True, text=True, timeout=60)
    assert out.returncode == 0, out.stderr
    return out.stdout.splitlines()


def fields(line):
    return dict(kv.split("=", 1) for kv in line.split()[1:])


def check_board_is_the_designs(d, send):
    """`send(lines)` -> the replies, on a board built for design `d`: `limits` is the design's
    ceiling, `material` its card, `cal` its FE calibration, and the console's parameters cannot
    raise the ceiling."""
    cal, paper, cal_paper, default, cal_default, grav, grav_dir, t_min, layers, lim, mat, *_, lim2 = send(
        ["cal", "preset paper", "cal", "preset default", "cal", "param grav", "param grav_dir", "param t_min", "param layers", "limits", "material", "param v_supply 100000", "param margin 0.99", "param z0 2", "limits"]
    )
    # the design's calibration round-trips from its TOML into the image's `cal` (6 decimals),
    # dropped by another finger and back with `preset default`; none without one
    none = "ok cal=1.000000,1.000000,1.000000,1.000000,1.000000,0.000000,1.000000,0.000000"
    assert cal == cal_default == ("ok cal=" + ",".join(f"{g:.6f}" for g in d.cal) if d.cal else none), (cal, d.cal)
    assert cal_paper == none, cal_paper
    # the board's default finger is the design's, in the design's orientation
    assert float(t_min.split("=")[1]) == pytest.approx(d.t_min) and float(layers.split("=")[1]) == d.layers, (t_min, layers)
    assert (float(grav.split("=")[1]), float(grav_dir.split("=")[1])) == (pytest.approx(d.grav), d.grav_dir), (grav, grav_dir)
    ceiling = d.finger().ceiling()
    vmax = [float(v) for v in fields(lim)["vmax"].split(",")]
    assert vmax == [pytest.approx(ceiling, abs=0.15)] * 3, (lim, ceiling)
    assert float(fields(lim)["vhold"]) == pytest.approx(min(ceiling, d.v_supply), abs=0.15)
    m = fields(mat)
    assert m["card"] == d.card and float(m["z0"]) == pytest.approx(d.z0) and float(m["margin"]) == pytest.approx(d.margin)
    # the design's ceiling is a board constant: the console's parameters cannot raise it
    assert [float(v) for v in fields(lim2)["vmax"].split(",")] == vmax, lim2


def test_the_design_file_builds_a_board_whose_ceiling_is_the_designs():
    path = ROOT / "designs" / "Elastosil-2030.toml"
    d = Design.load(path)
    assert d.cal is not None, "the design file carries its FE calibration (`python -m softfinger.design calibrate`)"
    # the board's console on the host (finger-sim: the firmware's application and its
    # board.rs constants, from the same build.rs), built for this design in its own target dir
    env = {**os.environ, "FINGER_DESIGN": str(path)}
    out = subprocess.run(["cargo", "build", "--quiet", "-p", "finger-sim", "--target", "host-tuple", "--target-dir", "target/design"], cwd=ROOT, env=env, capture_output=True, text=True)
    assert out.returncode == 0, out.stderr
    program = host_target_dir(ROOT / "target" / "design", "debug") / "finger-sim"
    check_board_is_the_designs(d, lambda lines: sim_lines(program, lines))


def test_a_design_calibration_the_model_refuses_stops_the_build(tmp_path):
    """build.rs checks a design's `cal` as the board's `cal` does (the model builds the design's
    finger with it): a factor below 0.1 stops the build with the reason; nothing is built."""
    d = Design.load(ROOT / "designs" / "Elastosil-2030.toml")
    path = tmp_path / "bad.toml"
    path.write_text(d.replace(cal=(1.0, 1.0, 1.0, 0.05, 1.0, 0.0, 1.0, 0.0)).to_toml())
    env = {**os.environ, "FINGER_DESIGN": str(path)}
    out = subprocess.run(["cargo", "build", "--quiet", "-p", "finger-sim", "--target", "host-tuple", "--target-dir", "target/design"], cwd=ROOT, env=env, capture_output=True, text=True)
    assert out.returncode != 0
    assert "cal = [1.0, 1.0, 1.0, 0.05" in out.stderr and "the model refuses it" in out.stderr and "0.1..10" in out.stderr, out.stderr[-2000:]


def test_the_design_file_builds_a_firmware_image_whose_limits_are_the_designs(tmp_path):
    """The command docs/design.md gives (`FINGER_DESIGN=designs/<card>.toml cargo build
    --release`): the image booted in QEMU answers with the design's card and ceiling. Built in
    the top's target dir (its dependencies are the default image's; only the firmware crate and
    its link build again), copied out, and the default image built back."""
    path = ROOT / "designs" / "VHB-4905.toml"
    d = Design.load(path)
    elf = ROOT / "target" / "thumbv7em-none-eabihf" / "release" / "finger-fw"
    try:
        out = subprocess.run(["cargo", "build", "--release", "--quiet", "--bin", "finger-fw"], cwd=ROOT, env={**os.environ, "FINGER_DESIGN": "designs/VHB-4905.toml"}, capture_output=True, text=True)
        assert out.returncode == 0, out.stderr
        image = tmp_path / "finger-fw-VHB-4905"
        shutil.copy(elf, image)
    finally:
        env = {k: v for k, v in os.environ.items() if k != "FINGER_DESIGN"}
        back = subprocess.run(["cargo", "build", "--release", "--quiet", "--bin", "finger-fw"], cwd=ROOT, env=env, capture_output=True, text=True)
        assert back.returncode == 0, back.stderr
    with sf.Board.qemu(image) as b:
        check_board_is_the_designs(d, lambda lines: [b.command(l) for l in lines])
    # built back: the default image is the paper's finger again (t_min 1.5 mm, 4 layers)
    with sf.Board.qemu(elf) as b:
        assert b.param("t_min")["t_min"] == pytest.approx(1.5) and b.param("layers")["layers"] == 4


def test_the_page_is_what_its_command_writes(tmp_path):
    """docs/design.md, its figure and designs/*.toml are what `report --from
    docs/design-results.json` writes (the run's numbers committed beside the page)."""
    import json

    from softfinger.design import report

    res = json.loads((ROOT / "docs" / "design-results.json").read_text())
    report.write(res, tmp_path)
    assert (tmp_path / "docs" / "design.md").read_text() == (ROOT / "docs" / "design.md").read_text()
    for card in res["cards"]:
        assert (tmp_path / "designs" / f"{card}.toml").read_text() == (ROOT / "designs" / f"{card}.toml").read_text()
    assert (tmp_path / "docs" / "design-pareto.png").read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"
    # the figure too: a regeneration with nothing changed gives no diff (no date, fixed ids)
    svg = (tmp_path / "docs" / "design-pareto.svg").read_text()
    assert "<svg" in svg[:2000] and "<dc:date>" not in svg
    assert svg == (ROOT / "docs" / "design-pareto.svg").read_text(), "docs/design-pareto.svg is not what `report --from docs/design-results.json` writes"
    again = tmp_path / "again"
    report.write(res, again)
    assert (again / "docs" / "design-pareto.png").read_bytes() == (tmp_path / "docs" / "design-pareto.png").read_bytes()
    page = (ROOT / "docs" / "design.md").read_text()
    assert "](design-pareto.png)" in page and "design-pareto.svg" in page


def test_a_design_checks_figures_are_plain_numbers():
    """`python -m softfinger.design fe` prints each check's ratios and errors: plain floats,
    not numpy scalars (their repr was `np.float64(1.27...)`). The FE results here are the
    model's own, 1 % stiffer: no CalculiX run."""
    from softfinger.design import fe

    d = Design.load(ROOT / "designs" / "VHB-4905.toml")
    results = [fe.CaseResult(c, True, tension_N=np.float64(c.tension_N) * 1.02, joints_rad=c.model_joints_rad, direct=tuple(np.float64(x) * 1.01 for x in c.model_direct)) for c in fe.cases_of(d)]
    ch = fe.DesignCheck(d, results)
    for figures in (ch.ratio("kyy"), ch.ratio("ktt"), ch.errors()):
        assert figures and all(type(v) is float for v in figures.values()), figures
        assert "np.float64" not in repr(figures)
    assert ch.errors()["kyy_pct"] == pytest.approx(100 * (1 / 1.01 - 1))
    # the FE at its own tension for the reference's tip angle (fe-design tip_deg=)
    assert all(c.tip_deg == pytest.approx(np.degrees(sum(c.model_joints_rad))) for c in fe.cases_of(d))
    assert ch.errors()["tension_pct"] == pytest.approx(100 * (1 / 1.02 - 1)) and ch.errors()["posture_deg"] == 0.0


def test_the_reference_posture_is_held_under_the_fingers_weight_horizontally():
    """The study judges a design held horizontally under its weight (`HORIZONTAL`): its
    reference posture is the 0 V posture of the reference's tip angle (3 x 10°), held at both
    ends of the tension interval by the inverse; a design whose weight alone bends it past that
    is infeasible, refused at the stage `reference`."""
    g = dict(grav=HORIZONTAL[0], grav_dir=HORIZONTAL[1])
    # the study's best VHB design without gravity (a 0.5 mm hinge) sags past it under its weight
    soft = Design.load(ROOT / "designs" / "VHB-4905.toml")
    assert evaluate("VHB-4905", [soft], grip=False).feasible[0]
    held = evaluate("VHB-4905", [soft], grip=False, **g)
    assert not held.feasible[0] and held.error[0] == "reference:Unreachable"
    f = soft.replace(cal=None, **g).finger()
    assert np.degrees(f.solve(0.0, [0, 0, 0], stiffness=False).joints_rad.sum()) > 30.0
    # a design that holds it: the 0 V end at the tension whose 0 V posture has the tip at 30°,
    # the other end the same posture by the inverse (every joint as at 0 V)
    d = Design(card="Elastosil-2030", t_min=0.5, a=8.7, e_b=26.0, w=10.0, layers=40, z0=0.09, v_supply=4500.0)
    ev = evaluate("Elastosil-2030", [d], grip=False, **g)
    assert ev.feasible[0], ev.error[0]
    r = ev.row(0)
    f = d.replace(**g).finger()
    q0 = f.solve(r["tension_hi_N"], [0, 0, 0], stiffness=False).joints_rad
    # (the inverse's 0 V end: the round trip's 0.01°)
    assert np.degrees(q0.sum()) == pytest.approx(30.0, abs=0.01)
    assert not np.allclose(q0, q0[0], atol=np.radians(0.5)), "the weight loads the joints unequally"
    top = f.pose(q0, P=r["tension_lo_N"])
    assert max(top.volts_V) == pytest.approx(r["volts_top_V"], rel=1e-3)
    back = f.solve(r["tension_lo_N"], top.volts_V, stiffness=False).joints_rad
    assert np.degrees(np.abs(back - q0)).max() < 0.01
    # fmax under gravity without the grip: at least the floor (the constraint's 0)
    assert r["fmax_N"] == 2.0 and r["c_fmax"] == 0.0
