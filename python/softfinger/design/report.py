"""docs/design.md, its Pareto figure (PNG and SVG) and designs/<card>.toml, from one run:
the Optuna study per card (resumed from its storage), the exhaustive grid sweep per card, the
Pareto front, the FE check of the front on a Dask LocalCluster with 2 workers and again with 1
(the benchmark), and the best design per card. ``python -m softfinger.design report`` runs it;
the run's numbers are kept in out/design/results.json and, beside the page, in
docs/design-results.json (``--from`` rewrites the page from them without running anything).

Not here: the search or the FE themselves (``study``, ``fe``).
"""

from __future__ import annotations

import json
import os
import platform
import time
from dataclasses import asdict
from pathlib import Path
from typing import Dict, List

import numpy as np

from . import fe
from .evaluate import CONSTRAINTS, FMAX_FLOOR_N, HORIZONTAL, OBJECTIVES, REFERENCE_DEG, evaluate
from .space import CARDS, LINK_B_MM, MARGIN, SPACE, Design, grid_size, variables
from .study import design_of_trial, feasible_trials, pareto_mask, run_study, storage_of, sweep

COMMAND = "target/pyenv/bin/python -m softfinger.design report"


def _snap(d: Design) -> Design:
    """A design's values on their buildable steps (Optuna's float steps carry binary noise)."""
    kw = {v.name: v.snap(getattr(d, v.name)) for v in variables(d.card)}
    kw["layers"] = int(kw["layers"])
    return d.replace(**kw)


def _front_rows(card: str, designs: List[Design], orientation=HORIZONTAL) -> List[Dict]:
    """Model rows (objectives, constraints, outputs) of `designs`, feasible ones only."""
    if not designs:
        return []
    g = dict(grav=orientation[0], grav_dir=orientation[1])
    ev = evaluate(card, designs, **g)
    # a supply above the card's hold ceiling is never used: the smallest on the step that
    # reaches the ceiling gives the same finger (the same objectives), and a smaller HV module
    step = next(v for v in variables(card) if v.name == "v_supply")
    tidy = []
    for i, d in enumerate(designs):
        c = float(ev.raw["ceiling_V"][i])
        if ev.feasible[i] and c < d.v_supply:
            d = d.replace(v_supply=max(step.low, step.step * np.ceil(c / step.step)))
        tidy.append(d)
    if tidy != designs:
        designs = list(dict.fromkeys(tidy))
        ev = evaluate(card, designs, **g)
    rows = []
    for i, d in enumerate(designs):
        if ev.feasible[i]:
            rows.append({"design": asdict(d), **ev.row(i)})
    return rows


class _Machine:
    """The machine while a stage runs: the load average (sampled each second) and the CPU time
    every process used (/proc/stat), so that what other jobs took is on record beside the
    stage's own CPU time."""

    def __enter__(self):
        import threading

        self.loads = [os.getloadavg()[0]]
        self.busy0 = self._busy()
        self._stop = threading.Event()
        self._t = threading.Thread(target=self._sample, daemon=True)
        self._t.start()
        return self

    def _sample(self):
        while not self._stop.wait(1.0):
            self.loads.append(os.getloadavg()[0])

    @staticmethod
    def _busy() -> float:
        """CPU seconds all processes have used since boot (every core), 0 where /proc is absent."""
        try:
            f = [int(x) for x in Path("/proc/stat").read_text().split("\n", 1)[0].split()[1:]]
        except OSError:
            return 0.0
        idle = f[3] + (f[4] if len(f) > 4 else 0)
        return (sum(f[:8]) - idle) / os.sysconf("SC_CLK_TCK")

    def __exit__(self, *exc):
        self._stop.set()
        self._t.join()
        self.busy1 = self._busy()

    def summary(self, wall: float, own_cpu: float) -> Dict:
        busy = self.busy1 - self.busy0
        return {"load_before": self.loads[0], "load_mean": float(np.mean(self.loads)), "load_max": float(max(self.loads)), "machine_cpu": busy, "others_cpu": max(0.0, busy - own_cpu)}


def run(root: Path, *, trials: int = 2048, batch: int = 64, grid: int = 7, fe_per_card: int = 5, fe_repeats: int = 2, storage: str | None = None, scheduler: str | None = None, progress: bool = True, search: Dict | None = None, orientation=HORIZONTAL) -> Dict:
    """Everything the page reports, as plain data (saved to out/design/results.json).
    `search`: a previous run's results whose search (studies, sweep, front) is kept; only the
    FE stage runs again."""
    out: Dict = {"machine": {"cores": os.cpu_count(), "python": platform.python_version(), "arch": platform.machine()}, "cards": {}, "orientation": list(orientation)}
    storage = storage or str(root / "out" / "design" / "studies.journal")
    chosen: List[Design] = []
    if search is not None:
        out["cards"] = search["cards"]
        for c in out["cards"].values():
            c["fe_designs"] = c["fe_designs"][:fe_per_card]
        chosen = [Design(**d) for c in out["cards"].values() for d in c["fe_designs"]]
    for card in CARDS if search is None else ():
        c: Dict = {}
        t0 = time.perf_counter()
        st = run_study(card, trials, storage_of(storage), batch=batch, progress=progress, orientation=orientation)
        c["study"] = {"trials": len(st.trials), "seconds_this_run": time.perf_counter() - t0, "feasible": len(feasible_trials(st)), "storage": str(storage), "sampler": "NSGA-II", "batch": batch}
        t0 = time.perf_counter()
        sw = sweep(card, grid, progress=progress, orientation=orientation)
        c["sweep"] = {"candidates": sw.candidates, "seconds": sw.seconds, "feasible": sw.feasible, "per_min": sw.rate_per_min, "grid": grid}
        # the front: the study's feasible trials and the sweep's non-dominated ones
        designs = [_snap(design_of_trial(card, t)) for t in feasible_trials(st)]
        if sw.evaluation is not None:
            designs += [sw.evaluation.design(i) for i in range(len(sw.evaluation))]
        designs = list(dict.fromkeys(designs))
        rows = _front_rows(card, designs, orientation)
        vals = np.array([[r[k] for k in OBJECTIVES] for r in rows]) if rows else np.zeros((0, 3))
        front = pareto_mask(vals) if len(rows) else np.zeros(0, dtype=bool)
        c["all"] = [[r["ratio_kyy"], r["ratio_ktt"], r["grip_N"]] for r in rows]
        c["front"] = [rows[i] for i in np.flatnonzero(front)]
        c["front"].sort(key=lambda r: -r["ratio_kyy"])
        c["best"] = c["front"][0] if c["front"] else None
        # FE: the best, then front designs spread over the grip force
        picks = c["front"][:1]
        rest = sorted(c["front"][1:], key=lambda r: r["grip_N"])
        if rest and fe_per_card > 1:
            idx = np.unique(np.linspace(0, len(rest) - 1, min(fe_per_card - 1, len(rest))).round().astype(int))
            picks += [rest[i] for i in idx]
        c["fe_designs"] = [p["design"] for p in picks]
        chosen += [Design(**p["design"]) for p in picks]
        out["cards"][card] = c
    # the FE stage, timed on a LocalCluster of as many workers as cores and of 1, alternately
    # (the benchmark; the first run's results are the report's), or once on `scheduler`
    cores = os.cpu_count() or 1
    order = [cores, 1] * fe_repeats if scheduler is None and cores > 1 else [cores]
    checks, timed = None, []
    for n in order:
        with _Machine() as mach:
            ch, wall, nw = fe.check(chosen, scheduler=scheduler, workers=n, progress=progress)
        checks = checks or ch
        cpu = sum(r.cpu_seconds for c in ch for r in c.results)
        timed.append({"workers": nw, "wall": wall, "cpu": cpu, **mach.summary(wall, cpu)})
    out["fe"] = {"kind": "3D half width, C3D20R, the coarse mesh with 16 columns per notch (`Density::coarse`, notch_cols of `fine`)", "runs": 2 * len(chosen), "timed": timed, "cores": cores, "scheduler": scheduler or "LocalCluster"}
    calibrate(out)
    out["fe"]["checks"] = [
        {
            "design": asdict(ch.design),
            "ok": ch.ok,
            "errors": ch.errors(),
            "ratio_kyy": ch.ratio("kyy"),
            "ratio_ktt": ch.ratio("ktt"),
            "ends": [{"end": r.case.end, "tension_N": r.case.tension_N, "fe_tension_N": r.tension_N, "ok": r.ok, "error": r.error, "seconds": r.seconds, "nodes": r.nodes, "model_direct": r.case.model_direct, "fe_direct": r.direct, "model_joints_deg": np.degrees(r.case.model_joints_rad).tolist(), "fe_joints_deg": np.degrees(r.joints_rad).tolist() if r.ok else []} for r in ch.results],
        }
        for ch in checks
    ]
    return out


def calibrate(res: Dict) -> None:
    """Each card's best design's FE calibration (``fe.calibrate``) into ``res["cards"][card]["cal"]``:
    designs/<card>.toml carries it, and the board built from it boots with it."""
    for c in res["cards"].values():
        if c.get("best"):
            try:
                c["cal"], c["cal_refused"] = list(fe.calibrate(Design(**c["best"]["design"]))), None
            except fe.CalibrationRefused as e:
                c["cal"], c["cal_refused"] = None, str(e)


def _judged(res: Dict) -> str:
    """The sentence on the orientation the run judged its designs in."""
    o = res.get("orientation")
    if not o or not o[0]:
        return "The study judges designs without gravity (`evaluate(..., grav=, grav_dir=)` takes one)."
    return (f"The study judges designs under their own weight ({o[0]:g} m/s², `grav_dir` {o[1]:g}°: held horizontally, `evaluate.HORIZONTAL`): the reference posture is the 0 V posture of the same tip angle "
            f"({REFERENCE_DEG:g}° a joint without gravity) at the tension that gives it, held at both ends by the inverse; a design whose weight alone bends it past that, or that cannot be held there, is infeasible.")


def _fmt_design(d: Dict) -> str:
    return f"t_min {d['t_min']:g} mm, a {d['a']:g} mm, E_b {d['e_b']:g} MPa, w {d['w']:g} mm, {d['layers']} × {d['z0']:g} mm layers, {d['v_supply'] / 1e3:g} kV supply"


def _check_of(res: Dict, design: Dict):
    for ch in res["fe"]["checks"]:
        if ch["design"] == design:
            return ch
    return None


def figure(res: Dict, png: Path, svg: Path) -> None:
    import matplotlib

    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    # the same figure from the same results, byte for byte: fixed SVG ids, no date nor version
    with matplotlib.rc_context({"svg.hashsalt": "softfinger-design-pareto"}):
        _draw(plt, res, png, svg)


def _draw(plt, res: Dict, png: Path, svg: Path) -> None:
    fig, axes = plt.subplots(1, 2, figsize=(11, 4.4))
    colors = {"VHB-4905": "tab:red", "Elastosil-2030": "tab:blue"}
    for card, c in res["cards"].items():
        allv = np.array(c["all"]) if c["all"] else np.zeros((0, 3))
        fr = np.array([[r["ratio_kyy"], r["ratio_ktt"], r["grip_N"]] for r in c["front"]]) if c["front"] else np.zeros((0, 3))
        for ax, j, name in ((axes[0], 0, "k_yy"), (axes[1], 1, "k_θθ")):
            ax.scatter(allv[:, 2], allv[:, j], s=4, color=colors[card], alpha=0.15, linewidths=0)
            ax.scatter(fr[:, 2], fr[:, j], s=18, color=colors[card], edgecolors="black", linewidths=0.4, label=f"{card}: Pareto front")
            fed = [ch for ch in res["fe"]["checks"] if ch["design"]["card"] == card and ch["ok"]]
            ax.scatter([next(r["grip_N"] for r in c["front"] if r["design"] == ch["design"]) for ch in fed], [ch["ratio_" + ("kyy" if j == 0 else "ktt")]["fe"] for ch in fed], marker="x", s=40, color=colors[card], label=f"{card}: FE (direct stiffness)")
            ax.set_xscale("log")
            ax.set_xlabel("grip force at fmax, N (log scale)")
            ax.set_ylabel(f"{name} ratio (max / min over the voltages)")
            ax.grid(alpha=0.3)
    axes[0].legend(fontsize=7, loc="upper right")
    fig.suptitle(f"Feasible designs (faint) and the Pareto front, reference posture {REFERENCE_DEG:g}° per joint")
    fig.tight_layout()
    png.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(png, dpi=110, metadata={"Software": None})
    fig.savefig(svg, metadata={"Date": None, "Creator": None})
    plt.close(fig)


def write(res: Dict, root: Path) -> None:
    """docs/design.md, docs/design-pareto.{png,svg}, designs/<card>.toml from `res`."""
    docs = root / "docs"
    figure(res, docs / "design-pareto.png", docs / "design-pareto.svg")
    # the numbers the page is written from, kept beside it (`--from docs/design-results.json`)
    (docs / "design-results.json").write_text(json.dumps(res, separators=(",", ":"), default=float) + "\n")
    (root / "designs").mkdir(exist_ok=True)
    L: List[str] = []
    w = L.append
    w(f"<!-- generated by `{COMMAND}`; do not edit -->")
    w("# Design study: which finger of this kind varies its stiffness, inside its HV safety bounds\n")
    bests = {card: c["best"] for card, c in res["cards"].items() if c["best"]}
    top_card = max(bests, key=lambda k: bests[k]["ratio_kyy"]) if bests else None
    if top_card:
        b = bests[top_card]
        ch = _check_of(res, b["design"])
        fe_txt = f"; CalculiX gives {ch['ratio_kyy']['fe']:.2f}× for the same design (the direct stiffness 1/C_yy: model {ch['ratio_kyy']['model']:.2f}×)" if ch and ch["ok"] else ""
        other = [f"{k} {v['ratio_kyy']:.2f}×" for k, v in bests.items() if k != top_card]
        w(
            f"**The largest stiffness change this finger gives inside its HV safety bounds is {b['ratio_kyy']:.2f}× in k_yy ({b['ratio_ktt']:.2f}× in k_θθ), "
            f"on {top_card} with {_fmt_design(b['design'])} (`designs/{top_card}.toml`){fe_txt}; the best on {', '.join(other)}. "
            f"Literature variable-stiffness joints reach 4-8× by electrostatic layer jamming (about 22× at best), 4-5.5× at finger level and up to ~10× where the DE is itself the load path: "
            f"the change this concept makes (its ratio's excess over 1, {b['ratio_kyy'] - 1:.2f}) is about {3.0 / (b['ratio_kyy'] - 1):.0f}× smaller than the smallest of theirs (4×: an excess of 3).**\n"
        )
    w("## What was searched\n")
    w(f"Each design is the paper's finger (n = 3, l = 27 mm, b = {10:g} mm, e = 5 mm; the model's defaults: m = 8, plate modulus, flexible links, uncalibrated) with these variables, per film card (`softfinger.design.space`):\n")
    w("| variable | VHB-4905 | Elastosil-2030 | grid (7 values) | why |")
    w("| --- | --- | --- | --- | --- |")
    for i, v in enumerate(SPACE["VHB-4905"]):
        e = SPACE["Elastosil-2030"][i]
        rng = lambda x: ", ".join(f"{c:g}" for c in x.choices) if x.choices else (f"{x.low:g}" if x.low == x.high else f"{x.low:g}..{x.high:g}" + (f" step {x.step:g}" if x.step else "") + (" (integer)" if x.integer else ""))
        grid = " / ".join(", ".join(f"{g:g}" for g in x.grid()) for x in ((v,) if v.grid() == e.grid() else (v, e)))
        w(f"| `{v.name}` ({v.unit}) | {rng(v)} | {rng(e)} | {grid} | {e.why} |")
    w(f"\nThe margin is the board's, {MARGIN:g}, on every design (a safety factor is not traded for stiffness). `paper-elastic` (the paper's 0.6 MPa as printed) is not a film and is not designed for.\n")
    w(f"**Objectives** (maximised): the tip stiffness ratio max/min of k_yy and of k_θθ (K_tip, `Finger::tip_stiffness`) at the reference posture, every joint at {REFERENCE_DEG:g}°, held by the inverse at both ends of its tension interval (one joint at the top voltage the ceiling allows, and 0 V: `inverse::stiffness_range`, as docs/inverse-tables.md); the grip force at fmax (the tip stopped where the 0 V end puts it, the cable pulled to fmax, `contact`).\n")
    w(f"**Constraints**, each a number the model computes, feasible at <= 0 (`softfinger.design.evaluate`): `refused` (the model refused the design at any step: its typed error, e.g. an unreachable posture or a branch end, counts as infeasible, never as a crash); `ceiling` (highest voltage used / the card's hold ceiling with the margin, capped by the supply, − 1); `breakdown` (highest field across a thinned layer / the card's breakdown field, − 1); `thinning` (2/3 − the thinnest stack's thickness stretch: the 33 % limit); `fmax` (fmax at both ends above {FMAX_FLOOR_N:g} N); `fits` (the stack, layers × z0, inside the notch depth (b − t_min)/2).\n")
    w("## Results per card\n")
    w("| card | study trials (feasible) | grid candidates (feasible) | best k_yy ratio | its k_θθ ratio | its grip N | its fmax N | ceiling V | thinning at the top % | FE: direct k_yy ratio, model / FE | FE: k_θθ, model / FE |")
    w("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    for card, c in res["cards"].items():
        b = c["best"]
        if not b:
            w(f"| {card} | {c['study']['trials']} ({c['study']['feasible']}) | {c['sweep']['candidates']:,} ({c['sweep']['feasible']:,}) | none feasible | | | | | | | |")
            continue
        ch = _check_of(res, b["design"])
        fe_y = f"{ch['ratio_kyy']['model']:.3f} / {ch['ratio_kyy']['fe']:.3f}" if ch and ch["ok"] else "failed"
        fe_t = f"{ch['ratio_ktt']['model']:.3f} / {ch['ratio_ktt']['fe']:.3f}" if ch and ch["ok"] else "failed"
        w(f"| {card} | {c['study']['trials']} ({c['study']['feasible']}) | {c['sweep']['candidates']:,} ({c['sweep']['feasible']:,}) | **{b['ratio_kyy']:.3f}** | {b['ratio_ktt']:.3f} | {b['grip_N']:.2f} | {b['fmax_N']:.2f} | {b['ceiling_V']:.0f} | {100 * (1 - b['s_min']):.1f} | {fe_y} | {fe_t} |")
    w("")
    for card, c in res["cards"].items():
        if c["best"]:
            w(f"- **{card}**: {_fmt_design(c['best']['design'])}: `designs/{card}.toml`.")
    w("\n![Pareto front](design-pareto.png)\n")
    w("[SVG](design-pareto.svg). Faint: every feasible design the study and the grid found; ringed: the Pareto front (the three objectives); crosses: the FE's ratio of the direct stiffness for the designs checked.\n")
    w("Why the ratios are small: the stack changes the joint's stiffness only by its own share of it, and the voltage changes that share only by the film's thinning at the ceiling (VHB 4905: 18 % at its hold ceiling, s_hold 0.818; Elastosil 2030: 4 %, docs/materials.md). A bonded stack's bending stiffness falls about as the cube of its thickness, so even a stack that carries the whole joint gives at most about 1/0.818³ = 1.8× on VHB 4905 and 1/0.959³ = 1.13× on Elastosil; the hinge's own TPU, the posture's tension and the fmax floor take part of that.\n")
    w("## FE check of the front\n")
    f = res["fe"]
    w(f"Each design's reference posture at both ends of its voltage range re-solved by CalculiX (`fe-design` in tools/calculix: NLGEOM, neo-Hookean body and stacks, the stacks at the thicknesses the end's voltages give, under the end's tension; {f['kind']}), then three small tip loads on top of it for the tip compliance C. Compared: the joint angles (the posture), and the tip's direct stiffness to a single load, 1/C_yy and 1/C_θθ, at each end and as a ratio over the ends. The model's K_tip entries (the objectives) invert the whole 3×3 compliance and amplify its small differences (and the FE's follower cable adds a geometric stiffness the model leaves out, docs/model.md \"Tip stiffness\"), so the check compares the quantity both compute directly; the table gives the objective (the model's K_tip ratio) beside it.\n")
    w("The stacks of the front nearly fill their notches (the stiffest change needs the thickest stack: the column *fill*, the stack's thickness at rest over the notch's depth (b − t_min)/2), so a stack's lens ends within a few µm of the notch's end, where the notch's face is vertical. The mesh takes such an end (closer to the notch's end than to the next column boundary) at the notch's end, its last element collapsed there, instead of a column a few µm wide beside the 10 mm link (tools/calculix mesh.rs, `columns`); that column made ccx cut back until it gave up on 3 of these 8 designs before, and the geometry it drops (a stack sliver of a few µm at the end, where its depth is nil) is below what a laminated stack is built to. A test solves both such stacks under the cable (tools/calculix tests/tip_compliance.rs).\n")
    w("Errors are model minus FE in % of FE: *joint* the worst joint angle over both ends; *1/C_yy*, *1/C_θθ* the worse end; *ratio* the ratio's error, *excess* the error of the ratio's excess over 1 (the part the voltage makes).\n")
    w("| card | design | fill % | objective: K_tip k_yy ratio | FE ok | joint % | 1/C_yy % | 1/C_θθ % | 1/C_yy ratio model / FE | excess % | 1/C_θθ ratio model / FE | excess % |")
    w("| --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- | --- |")
    objective = {json.dumps(r["design"], sort_keys=True): r["ratio_kyy"] for c in res["cards"].values() for r in c["front"]}
    for ch in f["checks"]:
        d = ch["design"]
        obj = objective.get(json.dumps(d, sort_keys=True), float("nan"))
        fill = f"{100 * d['layers'] * d['z0'] / ((LINK_B_MM - d['t_min']) / 2):.0f}"
        if not ch["ok"]:
            why = sorted({e["error"].split("*ERROR: ")[-1].split(" |")[0] for e in ch["ends"] if e["error"]})
            w(f"| {d['card']} | {_fmt_design(d)} | {fill} | {obj:.3f} | no: ccx: {'; '.join(why)} | | | | | | | |")
            continue
        e = ch["errors"]
        w(f"| {d['card']} | {_fmt_design(d)} | {fill} | {obj:.3f} | yes | {e['joint_pct']:+.1f} | {e['kyy_pct']:+.1f} | {e['ktt_pct']:+.1f} | {ch['ratio_kyy']['model']:.3f} / {ch['ratio_kyy']['fe']:.3f} | {e['excess_kyy_pct']:+.0f} | {ch['ratio_ktt']['model']:.3f} / {ch['ratio_ktt']['fe']:.3f} | {e['excess_ktt_pct']:+.0f} |")
    oks = [ch for ch in f["checks"] if ch["ok"]]
    held = [ch for ch in oks if "posture_deg" in ch["errors"]]
    if held:
        worst_p = max((ch["errors"]["posture_deg"] for ch in held), key=abs)
        worst_t = max((ch["errors"]["tension_pct"] for ch in held), key=abs)
        w(f"\nBoth ends at one posture in the FE too: each end's FE runs at its own tension for the reference posture's tip angle (`fe-design tip_deg=`: load steps around the model's tension, then secant runs to 0.01°), the stacks at the model's thicknesses. Over the {len(held)} designs, the FE's joints stand within {abs(worst_p):.2f}° of the reference posture's (worst {worst_p:+.2f}°: the tip angle is held, its split over the joints is the FE's), and the model's tension differs from the FE's by {worst_t:+.1f} % at worst (model minus FE, % of FE).\n")
    if oks:
        worst = max(abs(ch["errors"]["ratio_kyy_pct"]) for ch in oks)
        worst_t = max(abs(ch["errors"]["ratio_ktt_pct"]) for ch in oks)
        failed = len(f["checks"]) - len(oks)
        w(f"\nOver the {len(oks)} designs CalculiX solved{f' ({failed} did not converge)' if failed else ''}, the model's ratio of the direct stiffness is within {worst:.1f} % (1/C_yy) and {worst_t:.1f} % (1/C_θθ) of CalculiX's; the stiffnesses themselves differ more (the columns 1/C_yy and 1/C_θθ: the uncalibrated model on a coarse mesh), and that difference largely cancels in the ratio.\n")
    w("## From a design to a board\n")
    w(f"A design is a TOML file: `card` plus the console's parameter names (`t_min`, `a`, `e_b`, `w`, `layers`, `z0`, `v_supply`, `margin`, and the orientation the board is built for, `grav` and `grav_dir`: the board's, 9.81 m/s² hanging straight down, unless the file says otherwise; `softfinger.design.Design.to_toml`). {_judged(res)} The best design per card is `designs/<card>.toml`. The firmware builds for one with\n")
    w("```sh\nFINGER_DESIGN=designs/Elastosil-2030.toml cargo build --release\n```\n")
    w("build.rs reads the file (a relative path from the repository's top; an unknown key, a missing one, a value outside the model's range or `paper-elastic` stops the build with the reason) and writes the board constants src/board.rs includes: `BOARD_CARD`, `BOARD_Z0_MM`, `BOARD_LAYERS`, `BOARD_MARGIN`, the HV modules' `HV_FULL_SCALE_V` and `HV_LIMIT_V` (the design's supply) and `BOARD_FINGER` (the design's values, which the board's default parameters take, `preset default` too; `grav` and `grav_dir` optional, 0..20 m/s² and -180..180°, else the board's orientation) and `BOARD_CAL`, the design's FE calibration. Without `FINGER_DESIGN` the constants are the paper's finger on VHB 4905, as before. On that image `material` reports the design's card, z0 and margin, and `limits` its ceiling (`vmax` = `vhold` = the design's ceiling); they stay board constants: `param v_supply`, `param margin` or `param z0` can only lower the ceiling in force, never raise it past `vhold`.\n")
    w("**The design's FE calibration.** `cal = [h1, h2, h3, h4, ea0, ea1, ei0, ei1]` in the file (optional) are the factors of the console's `cal` (docs/fidelity-fe.md \"The calibration\"), computed for the design as `fe-calibrate` computes the default finger's (`fe-calibrate --card <card> --set <name>=<value> ...`: linear CalculiX unit loads on one element of the design, 3D half width, fine mesh, without gravity) by `python -m softfinger.design calibrate designs/<card>.toml` (or `calibrate --from docs/design-results.json` for each card's best design; `report` runs it). build.rs builds the design's finger with them as the board's `cal` does (`Finger::with_calibration`: every factor finite and within 0.1..10 at every stack thickness from the pull-in thickness to the rest thickness) and stops the build with the model's reason if it refuses them. The board boots with them: `cal` reads them, `preset default` restores them, and a `param` set of a mechanical parameter drops them as it drops the default finger's (the same rule, `Calibration::if_for`). The factors do not enter a ceiling (the hold ceiling and the thinning guard are the film's, docs/materials.md). Where the FE's element leaves that range the tool writes none and says why in the file's comment: the board runs the uncalibrated model.\n")
    w("Tests (`python/tests/test_design.py`, in `scripts/test`'s pytest): a 48-trial study finds a design that meets every constraint; designs the model refuses come back infeasible with their error, the other rows unchanged; a study killed (SIGKILL) mid-run resumes with every stored trial; `Finger` and `Design` pickle and round-trip; `designs/VHB-4905.toml` builds the firmware release image by the command above, which booted in QEMU answers `param` with the design's values, `material` with its card and `limits` with its ceiling, which `param` cannot raise (then the default image is built back; about two minutes, two LTO links); `designs/Elastosil-2030.toml` does the same on the board's application on the host (finger-sim, the same build.rs and board.rs constants), and its `cal` reads the file's factors (dropped by `preset paper`, back with `preset default`); a `cal` the model refuses stops the build with the reason; held horizontally under its weight, the study's best VHB design without gravity sags past the reference's tip angle (infeasible, stage `reference`) while a stiffer one holds it at both ends; this page, its figure (PNG and SVG) and designs/*.toml are what `--from docs/design-results.json` writes. tools/calculix tests/tip_compliance.rs solves two stacks that nearly fill their notches (the front's).\n")
    w("## Cost and benchmark\n")
    m = res["machine"]
    w(f"This machine: {m['cores']} cores (shared with other jobs while this ran: their CPU time is on record for the FE stage), {m['arch']}, Python {m['python']}. Heavy runs under `nice -n 10`.\n")
    w("| stage | work | wall time | rate |")
    w("| --- | --- | --- | --- |")
    tot_c, tot_s = 0, 0.0
    for card, c in res["cards"].items():
        s = c["sweep"]
        tot_c += s["candidates"]
        tot_s += s["seconds"]
        w(f"| grid sweep, {card} (no grip force) | {s['candidates']:,} candidates ({s['grid']} values per variable) | {s['seconds']:.0f} s | {s['per_min']:,.0f} candidates/min |")
    w(f"| grid sweep, both cards | {tot_c:,} candidates | {tot_s:.0f} s | {60 * tot_c / tot_s:,.0f} candidates/min |")
    for card, c in res["cards"].items():
        s = c["study"]
        if s["seconds_this_run"] > 1:
            w(f"| Optuna study, {card} (NSGA-II, batches of {s['batch']}, with the grip force; journal storage) | {s['trials']} trials | {s['seconds_this_run']:.0f} s (this run; resumed studies count only new trials) | {60 * s['trials'] / s['seconds_this_run']:,.0f} trials/min |")
        else:
            w(f"| Optuna study, {card} | {s['trials']} trials, resumed complete from its storage | - | - |")
    timed = f["timed"]
    for k, t in enumerate(timed):
        w(f"| FE stage, {t['workers']} worker(s) ({f['scheduler']}; run {k + 1} of {len(timed)}) | {f['runs']} ccx runs, {t['cpu']:.0f} CPU s of their own | {t['wall']:.0f} s | load average {t['load_before']:.1f} before, {t['load_mean']:.1f} mean (this stage's own runs included); other jobs took {t['others_cpu']:.0f} CPU s of the {f['cores'] * t['wall']:.0f} the cores had |")
    search_s = tot_s + sum(c["study"]["seconds_this_run"] for c in res["cards"].values())
    fe_s = sum(t["wall"] for t in timed)
    w(f"| the whole run (the searches above, the FE stage {len(timed)} times) | | {(search_s + fe_s) / 60:.1f} min ({search_s / 60:.1f} search, {fe_s / 60:.1f} FE) | |")
    by = {}
    for t in timed:
        by.setdefault(t["workers"], []).append(t["wall"])
    if 1 in by and f["cores"] in by and f["cores"] > 1:
        w1, wn = float(np.median(by[1])), float(np.median(by[f["cores"]]))
        sp = w1 / wn
        one = [t for t in timed if t["workers"] == 1]
        share = float(np.median([t["cpu"] / t["wall"] for t in one]))
        others = float(np.mean([t["others_cpu"] / (f["cores"] * t["wall"]) for t in timed]))
        w(
            f"\n**The FE stage's speed-up on Dask: {sp:.2f}× with {f['cores']} workers against 1** (the median wall times, {wn:.0f} s and {w1:.0f} s, "
            f"the stages run alternately, `nice -n 10`, as many workers as cores). The {f['runs']} runs are independent single-threaded ccx processes "
            f"({np.mean([t['cpu'] for t in one]) / f['runs']:.1f} CPU s each), so {f['cores']} workers can at most divide the wall time by {f['cores']}; "
            f"their own CPU time over the wall time says how many cores the stages' runs got: {share:.2f} with 1 worker, {float(np.median([t['cpu'] / t['wall'] for t in timed if t['workers'] == f['cores']])):.2f} with {f['cores']}, "
            f"while other jobs took {100 * others:.0f} % of the machine's CPU time on average. "
            + ("So the measured speed-up is close to what the machine allows." if sp >= 0.8 * f["cores"] else f"So the second worker found the second core mostly taken by other jobs: the shortfall is this shared machine's contention (the CPU time per run is the same with 1 and {f['cores']} workers). On {f['cores']} free cores the stage would take about {np.mean([t['cpu'] for t in one]) / f['cores']:.0f} s ({f['cores']}× less than on one); not measured, the machine had no idle moment this session.")
        )
    goal = 1_000_000
    rate = 60 * tot_c / tot_s
    w(f"\n**The goal of 1,000,000 candidates in 10 minutes**: the grid sweep evaluates {rate:,.0f} candidates per minute here (one candidate: the finger, the inverse's posture and tension interval, K_tip at both ends, fmax at both ends), so 1,000,000 take {goal / rate:.1f} minutes: the goal is {'met' if goal / rate <= 10 else 'not met'} without the grip force. The grip force (a pinned-tip contact solve at fmax) costs about 25× the rest of a candidate, so it is computed only for the sweep's non-dominated designs and in the study's trials. Optuna's own overhead (ask, tell, the storage) is about 10 ms a trial, so the sampler is for the search around the front, not for covering the space; the grid is.\n")
    w(f"Regenerate: `{COMMAND}` (the studies resume from out/design/studies.journal; `--trials`, `--grid`, `--scheduler tcp://host:8786` for a Dask cluster; `--fe-only out/design/results.json` keeps a run's search and times the FE stage again; `--from docs/design-results.json` rewrites this page, its figure and designs/*.toml from the numbers committed beside it, running nothing: a test checks that it gives this page byte for byte).\n")
    (docs / "design.md").write_text("\n".join(L) + "\n")
    for card, c in res["cards"].items():
        b = c["best"]
        if not b:
            continue
        d = Design(**b["design"]).replace(cal=c.get("cal"))
        ch = _check_of(res, b["design"])
        fe_txt = f"FE (CalculiX, direct stiffness 1/C_yy): model {ch['ratio_kyy']['model']:.3f}x, FE {ch['ratio_kyy']['fe']:.3f}x" if ch and ch["ok"] else "FE: not checked"
        comment = f"The best design on {card} of the design study (docs/design.md; generated by `{COMMAND}`).\nk_yy ratio {b['ratio_kyy']:.3f}x, k_tt ratio {b['ratio_ktt']:.3f}x at every joint {REFERENCE_DEG:g} deg; grip {b['grip_N']:.2f} N at fmax; ceiling {b['ceiling_V']:.0f} V.\n{fe_txt}.\nBuild the board for it: FINGER_DESIGN=designs/{card}.toml cargo build --release"
        if c.get("cal_refused"):
            comment += f"\nNo FE calibration: {c['cal_refused']}; the board built from it runs the uncalibrated model."
        (root / "designs" / f"{card}.toml").write_text(d.to_toml(comment))
