"""The paper's Fig. 4 scenes from Python: each scene file (scenes/*.toml, format in
docs/scenes.md) solved with softfinger and its postures drawn with matplotlib into a PNG.

    target/pyenv/bin/python python/examples/fig4.py                 # every scenes/*.toml -> out/python/
    target/pyenv/bin/python python/examples/fig4.py scenes/paper-de-0v.toml --out /tmp/figs

Per scene: one posture per tension (node 0, the nodes, the tip), in mm, the flexor side up; a
scene with a [match] section also gets the tension at which its finger reaches the tip angle
of the [match] finger (bisection; purple, wide and pale under the posture it coincides with)
and that finger's own posture (green, dotted). With two scenes or more, also
`fig4-compare.png`: every scene's posture at the largest tension they share on one axes, each
in its own colour, dash and marker, with a zoom on the tips and each tip angle in the legend,
so that the conditions that nearly coincide (0 V, one joint thinned, all thinned: tenths of a
degree apart) are told apart. The continuum reference overlay of finger-scene is not drawn here.
"""

from __future__ import annotations

import argparse
import sys
import tomllib
from pathlib import Path

import matplotlib

matplotlib.use("Agg")
import matplotlib.pyplot as plt
import numpy as np

import softfinger as sf

TOP = Path(__file__).resolve().parents[2]
NOT_PARAMS = {"preset", "volts", "thickness", "tension", "tensions", "show"}


def finger_of(section: dict) -> tuple[sf.Finger, np.ndarray | None, np.ndarray | None]:
    """The finger a [finger] or [match] section describes, and its volts or thickness."""
    params = {k: float(v) for k, v in section.items() if k not in NOT_PARAMS}
    f = sf.Finger(preset=section.get("preset", "default"), **params)
    volts = section.get("volts")
    thick = section.get("thickness")
    return f, None if volts is None else np.broadcast_to(np.asarray(volts, float), (f.n,)).copy(), \
        None if thick is None else np.broadcast_to(np.asarray(thick, float), (f.n,)).copy()


def drive_volts(f: sf.Finger, volts, thick) -> np.ndarray:
    if thick is not None:
        return f.volts_for_thickness(thick)  # ThicknessLimitError past the 33 % limit
    return np.zeros(f.n) if volts is None else volts


def tension_for_tip_angle(f: sf.Finger, volts, target_rad: float, solve_kw: dict) -> float:
    """The tension at which `f` reaches the tip angle `target_rad` (it grows with tension)."""
    lo, hi = 0.0, f.fmax(volts).tension_N * 0.999
    if f.solve(hi, volts, **solve_kw).tip[2] < target_rad:
        raise ValueError("the target tip angle is past this finger's branch end")
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        if f.solve(mid, volts, **solve_kw).tip[2] < target_rad:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def scene_finger(scene: dict):
    """A scene's finger, its voltages, tensions and solver options."""
    f, volts, thick = finger_of(scene.get("finger", {}))
    drive = scene.get("drive", {})
    if "volts" in drive or "thickness" in drive:
        volts = np.asarray(drive["volts"], float) if "volts" in drive else None
        thick = np.asarray(drive["thickness"], float) if "thickness" in drive else None
    v = drive_volts(f, volts, thick)
    tensions = np.atleast_1d(np.asarray(drive.get("tensions", drive.get("tension")), float))
    solver = scene.get("solver", {})
    solve_kw = {"method": solver.get("method", "converged")}
    if "n_inc" in solver:
        solve_kw["n_inc"] = int(solver["n_inc"])
    if "tol" in solver:
        solve_kw["tol"] = float(solver["tol"])

    return f, v, tensions, solve_kw


def run(path: Path, out: Path) -> Path:
    scene = tomllib.loads(path.read_text())
    f, v, tensions, solve_kw = scene_finger(scene)
    fig, ax = plt.subplots(figsize=(6.5, 4.5))
    sols = f.solve_many(tensions, v, **solve_kw)
    colors = plt.cm.viridis(np.linspace(0.0, 0.85, len(tensions)))
    for i, P in enumerate(tensions):
        xy = sols.nodes[i][:, :2]
        ax.plot(xy[:, 0], xy[:, 1], "-o", color=colors[i], ms=3, label=f"{P:g} N")
    if "match" in scene:
        m = scene["match"]
        g, gv, gt = finger_of(m)
        gv = drive_volts(g, gv, gt)
        target = g.solve(float(m["tension"]), gv, **solve_kw)
        P = tension_for_tip_angle(f, v, target.tip[2], solve_kw)
        xy = f.solve(P, v, **solve_kw).nodes[:, :2]
        # by construction it lies on a posture of the other finger: wide and pale, under it
        ax.plot(xy[:, 0], xy[:, 1], "-", color="purple", lw=7, alpha=0.3, zorder=1,
                label=f"{P:.3f} N: the match's tip angle (wide, under the posture it coincides with)")
        if m.get("show", True):
            t = target.nodes[:, :2]
            ax.plot(t[:, 0], t[:, 1], ":o", color="green", ms=3, label=f"match finger at {float(m['tension']):g} N")
    ax.set_aspect("equal")
    ax.set_xlabel("x, mm")
    ax.set_ylabel("y, mm (flexor side)")
    ax.set_title(scene.get("title", path.stem), fontsize=9)
    ax.grid(alpha=0.3)
    # beside the axes, where it covers no posture (inside, it hid the 1 N curves)
    ax.legend(fontsize=8, loc="upper left", bbox_to_anchor=(1.02, 1.0), borderaxespad=0.0)
    out.mkdir(parents=True, exist_ok=True)
    png = out / f"{path.stem}.png"
    fig.savefig(png, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return png


STYLES = [("-", "o"), ("--", "s"), ("-.", "^"), (":", "D"), ((0, (5, 1, 1, 1)), "v"), ((0, (1, 1)), "P"), ((0, (8, 2)), "X")]


def compare(paths: list[Path], out: Path) -> Path:
    """Every scene's posture at the largest tension they all have, on one axes, with a zoom on
    the tips: fig4-compare.png."""
    scenes = [(p, tomllib.loads(p.read_text())) for p in paths]
    rows = []
    for p, sc in scenes:
        f, v, tensions, solve_kw = scene_finger(sc)
        rows.append((p, sc, f, v, set(tensions.tolist()), solve_kw))
    common = set.intersection(*(r[4] for r in rows))
    P = max(common) if common else min(max(r[4]) for r in rows)
    fig, ax = plt.subplots(figsize=(7.5, 5.0))
    zoom = ax.inset_axes([0.03, 0.42, 0.36, 0.55])
    colors = plt.cm.tab10(np.arange(len(rows)) % 10)
    tips = []
    for i, (p, sc, f, v, _, solve_kw) in enumerate(rows):
        s = f.solve(P, v, **solve_kw)
        xy = s.nodes[:, :2]
        dash, mark = STYLES[i % len(STYLES)]
        # a scene's own colour notes ("; purple: ...") belong to its own figure, not to this one
        label = f"{sc.get('title', p.stem).split(';')[0]}: tip {np.degrees(s.tip[2]):.3f} deg"
        for a in (ax, zoom):
            a.plot(xy[:, 0], xy[:, 1], linestyle=dash, marker=mark, color=colors[i], ms=4, lw=1.4, label=label if a is ax else None)
        tips.append(xy[-1])
    tips = np.array(tips)
    c, r = tips.mean(axis=0), max(np.ptp(tips[:, 0]), np.ptp(tips[:, 1]), 0.5)
    zoom.set_xlim(c[0] - r, c[0] + r)
    zoom.set_ylim(c[1] - r, c[1] + r)
    zoom.set_aspect("equal")
    zoom.set_title("the tips, zoomed", fontsize=7)
    zoom.tick_params(labelsize=6)
    ax.indicate_inset_zoom(zoom, edgecolor="grey")
    ax.set_aspect("equal")
    ax.set_xlabel("x, mm")
    ax.set_ylabel("y, mm (flexor side)")
    ax.set_title(f"the compared conditions at {P:g} N", fontsize=9)
    ax.grid(alpha=0.3)
    ax.legend(fontsize=7, loc="upper center", bbox_to_anchor=(0.5, -0.2), ncol=1)
    out.mkdir(parents=True, exist_ok=True)
    png = out / "fig4-compare.png"
    fig.savefig(png, dpi=120, bbox_inches="tight")
    plt.close(fig)
    return png


def main() -> int:
    ap = argparse.ArgumentParser(description="the paper's Fig. 4 scenes as PNG postures")
    ap.add_argument("scenes", nargs="*", type=Path, help="scene files (default: every scenes/*.toml)")
    ap.add_argument("--out", type=Path, default=TOP / "out" / "python", help="output directory")
    args = ap.parse_args()
    scenes = args.scenes or sorted((TOP / "scenes").glob("*.toml"))
    status = 0
    ran = []
    for s in scenes:
        try:
            print(run(s, args.out))
            ran.append(s)
        except sf.FingerError as e:
            print(f"{s}: refused: {e}", file=sys.stderr)
            status = 1
    if len(ran) >= 2:
        print(compare(ran, args.out))
    return status


if __name__ == "__main__":
    sys.exit(main())
