"""The examples run: a Fig. 4 scene to PNG, and the pose sequence on the simulated board to CSV
(ending with HV at 0 after the stop)."""

import csv
import os
import subprocess
import sys
from pathlib import Path

from conftest import ROOT

EXAMPLES = ROOT / "python" / "examples"


def run(*args, env=None):
    out = subprocess.run([sys.executable, *map(str, args)], capture_output=True, text=True, timeout=300, env=env)
    assert out.returncode == 0, out.stderr
    return out


def test_fig4_scene_to_png(tmp_path):
    run(EXAMPLES / "fig4.py", ROOT / "scenes" / "paper-no-de.toml", ROOT / "scenes" / "paper-de-joint1-thin.toml", "--out", tmp_path)
    for name in ("paper-no-de", "paper-de-joint1-thin", "fig4-compare"):
        png = tmp_path / f"{name}.png"
        assert png.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n" and png.stat().st_size > 10_000
    # the paper's "2 mm to 1 mm" is refused, and the script says so
    out = subprocess.run([sys.executable, str(EXAMPLES / "fig4.py"), str(ROOT / "scenes" / "refused" / "paper-2mm-to-1mm.toml"), "--out", str(tmp_path)],
                         capture_output=True, text=True, timeout=120)
    assert out.returncode == 1 and "33 % pull-in limit" in out.stderr


def test_pose_sequence_logs_status_to_csv(tmp_path, sim_program):
    path = tmp_path / "seq.csv"
    run(EXAMPLES / "pose_sequence.py", "--out", path, "--settle", "5", env={**os.environ, "SOFTFINGER_SIM": str(sim_program)})
    rows = list(csv.DictReader(path.open()))
    done = [r for r in rows if r["result"] == "ok" and r["target_deg"] != "stop"]
    assert len(done) >= 5
    for r in done:
        want = [float(x) for x in r["target_deg"].split("/")]
        got = [float(r[f"joint{k}_deg"]) for k in (1, 2, 3)]
        assert all(abs(a - b) < 0.05 for a, b in zip(got, want)), r
        assert r["armed"] == "1" and float(r["force_N"]) > 0
    assert any(r["result"] == "err unreachable" for r in rows)
    last = rows[-1]
    assert last["target_deg"] == "stop" and last["armed"] == "0"
    assert [float(last[f"volts{k}_V"]) for k in (1, 2, 3)] == [0.0, 0.0, 0.0]
