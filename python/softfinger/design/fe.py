"""The FE check of chosen designs: each design's reference posture at both ends of its voltage
range re-solved by CalculiX (tools/calculix's ``fe-design``: the finger on the design's film,
its stacks at the thicknesses those voltages give, under that end's tension, then its tip
compliance there), as tasks on a ``dask.distributed`` cluster: a ``LocalCluster`` by default,
any scheduler by address (``tcp://host:8786``) for a lab's cluster. A task carries the design
(a picklable dataclass) and the model's answers it is compared with; the worker needs the
package, ``ccx`` and the ``fe-design`` binary (``$SOFTFINGER_FE`` or the repository's build).

Compared, model against FE, per end: the joint angles (the posture), and the tip's direct
stiffness to a single load, 1/C_yy (N/mm) and 1/C_θθ (N·mm/rad), C the tip compliance (the
tip free in the other directions); per design the ratio of each over the two ends. The
model's K_tip entries (the study's objectives) invert the whole 3x3 compliance and amplify its
small differences, so the check compares what both compute directly.

Not here: which designs (``report`` picks the Pareto front), the cluster's set-up beyond
``LocalCluster``.
"""

from __future__ import annotations

import os
import resource
import shutil
import subprocess
import time
from dataclasses import dataclass, field
from pathlib import Path
from typing import Dict, List, Optional, Sequence

import numpy as np

from .evaluate import REFERENCE_DEG
from .space import Design

def repo_root() -> Path:
    """The repository around the working directory or around this package (its venv is in
    the repository's target/)."""
    for start in (Path.cwd(), Path(__file__).resolve()):
        for d in [start, *start.parents]:
            if (d / "tools" / "calculix" / "Cargo.toml").exists():
                return d
    raise RuntimeError("not inside the repository: run from it, or set SOFTFINGER_FE")


def fe_program(name: str = "fe-design") -> Path:
    """A tools/calculix binary (``fe-design``: ``$SOFTFINGER_FE`` if set), else the repository's
    release build (built here if missing: ``cargo build --release --bin <name>`` in
    tools/calculix)."""
    env = os.environ.get("SOFTFINGER_FE")
    if env and name == "fe-design":
        return Path(env)
    host = subprocess.run(["rustc", "--print", "host-tuple"], capture_output=True, text=True, check=True).stdout.strip()
    root = repo_root()
    p = root / "target" / host / "release" / name
    if not p.is_file():
        subprocess.run(["cargo", "build", "--release", "--quiet", "--bin", name], cwd=root / "tools" / "calculix", check=True)
    return p


class CalibrationRefused(RuntimeError):
    """The design's FE calibration leaves the range the model (and the board's ``cal``)
    accepts: factors finite and 0.1..10 at every stack thickness. Nothing is written."""


def calibrate(design: Design) -> tuple:
    """The design's FE calibration factors (``fe-calibrate --card <card> --set ...``: linear
    CalculiX unit loads on one element, 3D half width, fine mesh, without gravity as the
    calibration is defined, docs/fidelity-fe.md): the 8 of the console's ``cal`` line, which
    the design's TOML carries and the board built from it boots with."""
    if shutil.which("ccx") is None:
        raise RuntimeError("ccx not found: scripts/setup installs calculix-ccx")
    args = [str(fe_program("fe-calibrate")), "--card", design.card]
    for k, v in design.params().items():
        args += ["--set", f"{k}={v!r}"]
    out = subprocess.run(args, capture_output=True, text=True, env={**os.environ, "OMP_NUM_THREADS": "1"})
    if out.returncode != 0:
        why = (out.stderr.strip().splitlines() or ["?"])[-1].removeprefix("error: ")
        if "cal out of range" in why:
            raise CalibrationRefused(why)
        raise RuntimeError(f"fe-calibrate failed for {design}: {why}")
    line = next(l for l in out.stdout.splitlines() if l.startswith("cal "))
    return tuple(float(x) for x in line.split()[1:])


@dataclass(frozen=True)
class Case:
    """One FE run: a design at one end of its reference posture."""

    design: Design
    end: str  # "top" (the ceiling's end: softest stacks) or "0V"
    tension_N: float
    stack_mm: tuple
    model_joints_rad: tuple
    model_direct: tuple  # (1/C_yy N/mm, 1/C_θθ N·mm/rad), the model's
    kind: str = "3d"
    density: str = "notch"
    #: the reference posture's tip angle, degrees: the FE runs at its own tension for it
    #: (``fe-design tip_deg=``, the model's tension the first guess); None: at the model's
    tip_deg: Optional[float] = None


@dataclass
class CaseResult:
    case: Case
    ok: bool
    tension_N: float = 0.0  # the FE's (= the model's without tip_deg)
    joints_rad: tuple = ()
    direct: tuple = ()  # (1/C_yy, 1/C_θθ), FE
    seconds: float = 0.0
    cpu_seconds: float = 0.0  # the run's processes' CPU time (user + system)
    nodes: int = 0
    error: str = ""


def run_case(case: Case, program: Optional[str] = None) -> CaseResult:
    """Run one case with CalculiX (a Dask task: plain data in, plain data out)."""
    prog = program or str(fe_program())
    d = case.design
    args = [prog, f"card={d.card}"] + [f"{k}={v}" for k, v in d.params().items()]
    args += [f"tension={case.tension_N!r}", "stack=" + ",".join(repr(float(x)) for x in case.stack_mm), f"kind={case.kind}", f"density={case.density}"]
    if case.tip_deg is not None:
        args.append(f"tip_deg={case.tip_deg!r}")
    t0, r0 = time.perf_counter(), resource.getrusage(resource.RUSAGE_CHILDREN)
    out = subprocess.run(args, capture_output=True, text=True, env={**os.environ, "OMP_NUM_THREADS": "1"})
    secs, r1 = time.perf_counter() - t0, resource.getrusage(resource.RUSAGE_CHILDREN)
    cpu = (r1.ru_utime - r0.ru_utime) + (r1.ru_stime - r0.ru_stime)
    if out.returncode != 0:
        return CaseResult(case, False, seconds=secs, cpu_seconds=cpu, error=(out.stderr.strip().splitlines() or ["?"])[-1])
    kv = dict(line.split("=", 1) for line in out.stdout.split() if "=" in line)
    num = lambda k: [float(x) for x in kv[k].split(",")]
    c = np.array(num("compliance")).reshape(3, 3)
    return CaseResult(case, True, tension_N=num("tension")[0], joints_rad=tuple(num("joints")), direct=(1.0 / c[1, 1], 1.0 / c[2, 2]), seconds=secs, cpu_seconds=cpu, nodes=int(kv["nodes"]))


def cases_of(design: Design, *, kind: str = "3d", density: str = "notch", reference_deg: float = REFERENCE_DEG, fe_tension: bool = True) -> List[Case]:
    """The two FE cases of a design: its reference posture by the model's inverse at both ends
    of the tension interval (the ends `evaluate` takes its ratios at), without gravity (the FE
    check's cases have none). `fe_tension`: each end's FE at its own tension for the reference
    posture's tip angle (the stacks at the model's thicknesses), so that both ends compare one
    posture in the FE too; else at the model's tension."""
    f = design.replace(grav=0.0).finger()
    angles = [reference_deg] * f.n
    q = f.pose(angles, degrees=True)
    out = []
    for end, P in (("top", float(q.interval_N[0])), ("0V", float(q.interval_N[1]))):
        s = f.pose(angles, P=P, degrees=True)
        sol = f.solve(P, s.volts_V)
        c = np.linalg.inv(sol.stiffness)
        tip = float(np.degrees(np.sum(sol.joints_rad))) if fe_tension else None
        out.append(Case(design, end, P, tuple(float(x) for x in s.thickness_mm), tuple(float(x) for x in sol.joints_rad), (1.0 / c[1, 1], 1.0 / c[2, 2]), kind, density, tip))
    return out


@dataclass
class DesignCheck:
    """A design's FE check: both ends' results and the model-vs-FE errors (%)."""

    design: Design
    results: List[CaseResult]

    @property
    def ok(self) -> bool:
        return all(r.ok for r in self.results)

    def ratio(self, which: str) -> Dict[str, float]:
        """The ratio max/min over the two ends of the direct stiffness `which` ("kyy" or
        "ktt"), model and FE."""
        j = 0 if which == "kyy" else 1
        m = [r.case.model_direct[j] for r in self.results]
        out = {"model": float(max(m) / min(m))}
        if self.ok:
            fe = [r.direct[j] for r in self.results]
            out["fe"] = float(max(fe) / min(fe))
        return out

    def errors(self) -> Dict[str, float]:
        """Model minus FE in % of FE: the worst joint angle, each end's direct stiffnesses, the
        ratios (of the ratio's excess over 1 too: the part the voltage makes)."""
        if not self.ok:
            return {}
        e: Dict[str, float] = {}
        e["joint_pct"] = max((100.0 * (m / f - 1.0) for r in self.results for m, f in zip(r.case.model_joints_rad, r.joints_rad)), key=abs)
        # the FE's posture against the reference (degrees) and its tension against the model's
        e["posture_deg"] = max((float(np.degrees(f - m)) for r in self.results for m, f in zip(r.case.model_joints_rad, r.joints_rad)), key=abs)
        if all(r.tension_N > 0 for r in self.results):
            e["tension_pct"] = max((100.0 * (r.case.tension_N / r.tension_N - 1.0) for r in self.results), key=abs)
        for j, name in enumerate(("kyy", "ktt")):
            e[f"{name}_pct"] = max((100.0 * (r.case.model_direct[j] / r.direct[j] - 1.0) for r in self.results), key=abs)
            rr = self.ratio(name)
            e[f"ratio_{name}_pct"] = 100.0 * (rr["model"] / rr["fe"] - 1.0)
            e[f"excess_{name}_pct"] = 100.0 * ((rr["model"] - 1.0) / (rr["fe"] - 1.0) - 1.0) if rr["fe"] > 1.0 else float("nan")
        return {k: float(v) for k, v in e.items()}


def client_of(scheduler: Optional[str] = None, workers: int = 2):
    """A Dask client: to `scheduler` (an address) or to a new LocalCluster of `workers`
    single-threaded processes. Returns (client, cluster or None)."""
    from dask.distributed import Client, LocalCluster

    if scheduler:
        return Client(scheduler), None
    cluster = LocalCluster(n_workers=workers, threads_per_worker=1, processes=True, dashboard_address=None)
    return Client(cluster), cluster


def check(designs: Sequence[Design], *, scheduler: Optional[str] = None, workers: int = 2, kind: str = "3d", density: str = "notch", progress: bool = True):
    """FE-check `designs` on a Dask cluster; returns ([DesignCheck], wall seconds of the FE
    stage, the cluster's worker count)."""
    from dask.distributed import as_completed
    from tqdm import tqdm

    all_cases = [c for d in designs for c in cases_of(d, kind=kind, density=density)]
    program = str(fe_program())
    if shutil.which("ccx") is None:
        raise RuntimeError("ccx not found: scripts/setup installs calculix-ccx")
    client, cluster = client_of(scheduler, workers)
    try:
        nworkers = len(client.scheduler_info()["workers"])
        t0 = time.perf_counter()
        futures = client.map(run_case, all_cases, program=program, pure=False)
        done: Dict[int, CaseResult] = {}
        index = {f.key: i for i, f in enumerate(futures)}
        for fut in tqdm(as_completed(futures), total=len(futures), desc=f"FE on {nworkers} worker(s)", unit="run", disable=not progress):
            done[index[fut.key]] = fut.result()
        wall = time.perf_counter() - t0
    finally:
        client.close()
        if cluster is not None:
            cluster.close()
    results = [done[i] for i in range(len(all_cases))]
    checks = [DesignCheck(d, results[2 * i : 2 * i + 2]) for i, d in enumerate(designs)]
    return checks, wall, nworkers
