"""``python -m softfinger.design``: the design study's command line (docs/design.md).

- ``study --card C [--trials N] [--storage PATH|URL] [--batch B] [--sampler nsga2|tpe]``: run or
  resume a card's Optuna study (journal file out/design/studies.journal by default);
- ``sweep --card C [--grid 7]``: the exhaustive grid, its rate and best design;
- ``fe DESIGN.toml ... [--scheduler tcp://...] [--workers 2]``: FE-check designs on Dask;
- ``calibrate [DESIGN.toml ...] [--from results.json]``: the designs' FE calibration factors
  (``fe-calibrate``), written into their TOML files (``cal``), or into a report's results
  for each card's best design, then the page and designs/<card>.toml rewritten from them;
- ``report [--trials N] [--grid 7] [--fe-repeats 2] [--scheduler ...] [--from results.json | --fe-only results.json]``: everything, then
  docs/design.md, its figure and designs/<card>.toml.
"""

from __future__ import annotations

import argparse
import json
import sys
from pathlib import Path

from .fe import repo_root
from .space import CARDS, Design


def main(argv=None) -> int:
    ap = argparse.ArgumentParser(prog="python -m softfinger.design", description="The design study (docs/design.md).")
    sub = ap.add_subparsers(dest="cmd", required=True)
    s = sub.add_parser("study", help="run or resume a card's Optuna study")
    s.add_argument("--card", choices=CARDS, required=True)
    s.add_argument("--trials", type=int, default=2048)
    s.add_argument("--storage", default=None, help="a journal file (default out/design/studies.journal) or an RDB URL (sqlite:///x.db)")
    s.add_argument("--batch", type=int, default=64)
    s.add_argument("--sampler", choices=("nsga2", "tpe"), default="nsga2")
    s.add_argument("--seed", type=int, default=0)
    g = sub.add_parser("sweep", help="the exhaustive grid of a card")
    g.add_argument("--card", choices=CARDS, required=True)
    g.add_argument("--grid", type=int, default=7)
    f = sub.add_parser("fe", help="FE-check designs (TOML files) on a Dask cluster")
    f.add_argument("designs", nargs="+")
    f.add_argument("--scheduler", default=None, help="a Dask scheduler's address (default: a LocalCluster)")
    f.add_argument("--workers", type=int, default=2)
    c = sub.add_parser("calibrate", help="FE calibration factors of designs, into their TOML files (or a report's results)")
    c.add_argument("designs", nargs="*")
    c.add_argument("--from", dest="from_json", default=None, help="a report's results.json: calibrate each card's best design, then rewrite the page and designs/*.toml")
    r = sub.add_parser("report", help="everything, then docs/design.md, its figure and designs/<card>.toml")
    r.add_argument("--trials", type=int, default=2048)
    r.add_argument("--grid", type=int, default=7)
    r.add_argument("--fe-per-card", type=int, default=5)
    r.add_argument("--fe-repeats", type=int, default=2, help="FE stage timings per worker count (alternating cores and 1)")
    r.add_argument("--storage", default=None)
    r.add_argument("--scheduler", default=None)
    r.add_argument("--from", dest="from_json", default=None, help="rewrite the page from a results.json, running nothing")
    r.add_argument("--fe-only", dest="fe_only", default=None, help="keep the search of a results.json, run the FE stage again")
    for p_ in (s, g, r):
        p_.add_argument("--grav", type=float, default=None, help="gravity, m/s² (default: evaluate.HORIZONTAL's; 0: none)")
        p_.add_argument("--grav-dir", type=float, default=None, help="gravity's direction, degrees (default: evaluate.HORIZONTAL's, 90: held horizontally)")
    a = ap.parse_args(argv)
    if a.cmd in ("study", "sweep", "report"):
        from .evaluate import HORIZONTAL

        orientation = (HORIZONTAL[0] if a.grav is None else a.grav, (HORIZONTAL[1] if a.grav_dir is None else a.grav_dir) if (a.grav is None or a.grav) else 0.0)
    root = repo_root()
    if a.cmd == "study":
        from .study import feasible_trials, run_study, storage_of

        st = run_study(a.card, a.trials, storage_of(a.storage or root / "out" / "design" / "studies.journal"), batch=a.batch, seed=a.seed, sampler=a.sampler, orientation=orientation)
        ft = feasible_trials(st)
        best = max(ft, key=lambda t: t.values[0], default=None)
        print(f"{len(st.trials)} trials, {len(ft)} feasible" + (f"; best k_yy ratio {best.values[0]:.4f}: {best.params}" if best else ""))
    elif a.cmd == "sweep":
        from .study import sweep

        sw = sweep(a.card, a.grid, orientation=orientation)
        print(f"{sw.candidates:,} candidates in {sw.seconds:.1f} s ({sw.rate_per_min:,.0f}/min), {sw.feasible:,} feasible")
        ev = sw.evaluation
        if ev is not None and len(ev):
            i = int(ev.objectives[:, 0].argmax())
            print(f"best k_yy ratio {ev.objectives[i, 0]:.4f} (k_tt {ev.objectives[i, 1]:.4f}, grip {ev.objectives[i, 2]:.2f} N): {ev.design(i)}")
    elif a.cmd == "fe":
        from . import fe

        designs = [Design.load(p) for p in a.designs]
        checks, wall, n = fe.check(designs, scheduler=a.scheduler, workers=a.workers)
        print(f"FE stage: {wall:.1f} s on {n} worker(s)")
        def fmt(d: dict) -> str:
            return ", ".join(f"{k} {v:.4g}" for k, v in d.items())

        for ch in checks:
            state = "ok" if ch.ok else "FE failed: " + "; ".join(str(r.error) for r in ch.results if r.error)
            print(f"{ch.design.card}: {state}; k_yy ratio (direct): {fmt(ch.ratio('kyy'))}; model - FE, % of FE: {fmt(ch.errors()) or '-'}")
    elif a.cmd == "calibrate":
        from . import fe, report

        refused = 0
        for path in a.designs:
            d = Design.load(path)
            head = []
            for line in Path(path).read_text().splitlines():
                if not line.startswith("#") or line.startswith("# FE calibration"):
                    break
                head.append(line[1:].strip())
            try:
                d = d.replace(cal=fe.calibrate(d))
            except fe.CalibrationRefused as e:
                print(f"{path}: no FE calibration, file unchanged: {e}")
                refused += 1
                continue
            Path(path).write_text(d.to_toml("\n".join(head)))
            print(f"{path}: cal " + " ".join(f"{g:.6f}" for g in d.cal))
        if a.from_json:
            res = json.loads(Path(a.from_json).read_text())
            report.calibrate(res)
            report.write(res, root)
            for card, c in res["cards"].items():
                print(f"{card}: " + ("cal " + " ".join(f"{g:.6f}" for g in c["cal"]) if c.get("cal") else f"no FE calibration: {c.get('cal_refused')}"))
        if not a.designs and not a.from_json:
            ap.error("calibrate: design files or --from results.json")
        return 1 if refused else 0
    elif a.cmd == "report":
        from . import report

        if a.from_json:
            res = json.loads(Path(a.from_json).read_text())
        else:
            search = json.loads(Path(a.fe_only).read_text()) if a.fe_only else None
            res = report.run(root, trials=a.trials, grid=a.grid, fe_per_card=a.fe_per_card, fe_repeats=a.fe_repeats, storage=a.storage, scheduler=a.scheduler, search=search, orientation=orientation)
            out = root / "out" / "design" / "results.json"
            out.parent.mkdir(parents=True, exist_ok=True)
            out.write_text(json.dumps(res, indent=1, default=float))
        report.write(res, root)
        print("wrote docs/design.md, docs/design-pareto.png, docs/design-pareto.svg, designs/*.toml")
    return 0


if __name__ == "__main__":
    sys.exit(main())
