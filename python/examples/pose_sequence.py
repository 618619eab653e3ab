"""Drive the simulated board through a pose sequence and log its `status` to CSV.

    target/pyenv/bin/python python/examples/pose_sequence.py [--out out/python/pose-sequence.csv] [--qemu]

For each target posture (joint angles in degrees) the board's own inverse (`pose`, armed) sets
the cable tension and the three channel voltage targets (its reply says `moved=1`), the board
is given time to slew (`wait`), and its `status` is logged (the posture at the stacks'
thickness then: the film still creeps toward the target, `pose`'s `settle`). A posture the board refuses is
logged with its error code and skipped. Leaving the `with` block (at the end, on an error or
on Ctrl-C) sends `stop`; the final row is the board's status after it.
"""

from __future__ import annotations

import argparse
import csv
from pathlib import Path

import softfinger as sf

TOP = Path(__file__).resolve().parents[2]

#: target joint angles, degrees: a bend and back, each a posture the board's finger reaches
#: hanging under its weight (issue 53: the stacks change a joint's stiffness by 1 %, so its
#: angles grow toward the tip; each is its `solve` at 0.25-1 N, every stack at 3,800 V); (6, 4, 2)
#: asks the stacks for more than they can give (the board answers `err unreachable`, logged)
SEQUENCE = [(2.30, 2.64, 3.06), (4.66, 5.35, 6.21), (7.08, 8.15, 9.47), (6, 4, 2), (9.58, 11.04, 12.84), (7.08, 8.15, 9.47), (4.66, 5.35, 6.21), (2.30, 2.64, 3.06)]


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.split("\n")[0])
    ap.add_argument("--out", type=Path, default=TOP / "out" / "python" / "pose-sequence.csv")
    ap.add_argument("--qemu", action="store_true", help="the emulator image instead of finger-sim")
    ap.add_argument("--settle", type=float, default=5.0, help="seconds to wait after each command (slew)")
    args = ap.parse_args()
    args.out.parent.mkdir(parents=True, exist_ok=True)
    board = sf.Board.qemu() if args.qemu else sf.Board.sim()
    t = 0.0
    with open(args.out, "w", newline="") as fh, board as b:
        w = csv.writer(fh)
        w.writerow(["t_s", "target_deg", "result", *sf.Status.COLUMNS])
        lim = b.limits()
        b.arm()
        for target in SEQUENCE:
            try:
                ans = b.pose(*target)
            except sf.BoardError as e:
                w.writerow([t, "/".join(map(str, target)), f"err {e.code}"])
                continue
            # armed, the board's `pose` set the tension and the voltage targets itself
            assert ans.moved, ans
            assert all(v < m for v, m in zip(ans.volts_V, lim.vmax_V)), "the board's inverse stays below its ceilings"
            b.wait(args.settle)
            t += args.settle
            w.writerow([t, "/".join(map(str, target)), "ok", *b.status().row()])
    st = board.final_status
    with open(args.out, "a", newline="") as fh:
        csv.writer(fh).writerow([t, "stop", "ok", *(st.row() if st else [])])
    print(f"wrote {args.out}")


if __name__ == "__main__":
    main()
