"""The search over the design space: an Optuna multi-objective study per card (NSGA-II or TPE,
with the constraints through ``constraints_func``), asked and told in batches so that each
batch is one parallel model call; resumable in an Optuna storage (a journal file by default,
SQLite or any RDB URL); and the exhaustive grid sweep (7 values per variable) that the headline
rests on, with its rate.

Not here: the objectives and constraints (``evaluate``), the FE check (``fe``).
"""

from __future__ import annotations

import itertools
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, List, Optional, Tuple

import numpy as np

from .evaluate import CONSTRAINTS, HORIZONTAL, OBJECTIVES, Evaluation, evaluate
from .space import MARGIN, Design, variables


def storage_of(where: str | Path):
    """An Optuna storage: an RDB URL as it is (``sqlite:///x.db``, ``postgresql://...``: many
    workers), anything else a journal file (one writer, or several on one file system)."""
    import optuna
    from optuna.storages.journal import JournalFileBackend, JournalStorage

    s = str(where)
    if "://" in s:
        return s
    Path(s).parent.mkdir(parents=True, exist_ok=True)
    return JournalStorage(JournalFileBackend(s))


def sampler_of(name: str, seed: int, population: int):
    """NSGA-II (population = the batch) or multivariate TPE; both read each trial's constraints
    (``Trial.set_constraint``, which Optuna 5 puts in place of ``constraints_func``)."""
    import optuna

    if name == "nsga2":
        return optuna.samplers.NSGAIISampler(population_size=population, seed=seed)
    if name == "tpe":
        return optuna.samplers.TPESampler(seed=seed, multivariate=True)
    raise ValueError(f"sampler {name!r}: nsga2 or tpe")


def suggest(trial, card: str) -> Dict[str, float]:
    """One candidate's variables from a trial (buildable values: on each variable's step)."""
    out = {}
    for v in variables(card):
        if v.choices is not None:
            out[v.name] = float(trial.suggest_categorical(v.name, list(v.choices)))
        elif v.integer:
            out[v.name] = float(trial.suggest_int(v.name, int(v.low), int(v.high), log=v.log))
        else:
            out[v.name] = float(trial.suggest_float(v.name, v.low, v.high, step=v.step))
    return out


def study_name(card: str, orientation: Tuple[float, float] = (0.0, 0.0)) -> str:
    """A card's study in one orientation (a storage keeps each apart: their trials differ)."""
    return f"design-{card}" if not orientation[0] else f"design-{card}-grav{orientation[0]:g}-dir{orientation[1]:g}"


def run_study(card: str, n_trials: int, storage, *, batch: int = 64, seed: int = 0, sampler: str = "nsga2", progress: bool = True, stop_after: Optional[int] = None, orientation: Tuple[float, float] = HORIZONTAL):
    """Run (or resume) the study of `card` in `storage` until it holds `n_trials` trials.

    Each batch of `batch` trials is asked and told in an in-memory study that mirrors the
    stored one (the sampler sees every stored trial), evaluated in one model call, then written
    to the storage one finished trial per record (``Study.add_trials``): the storage never holds
    an unfinished trial, so a killed run loses only the batch it was evaluating, and a restart
    goes on from the stored trials. (Asking and telling against a journal file or SQLite
    directly costs 10-100 ms a trial in Optuna's storage layer, far more than the model.)
    `stop_after`: return after this many batches. `orientation`: (grav m/s², grav_dir degrees)
    every candidate is judged in (``evaluate.HORIZONTAL``; (0, 0) without gravity). Returns the
    stored study."""
    import optuna
    from optuna.trial import TrialState
    from tqdm import tqdm

    optuna.logging.set_verbosity(optuna.logging.WARNING)
    directions = ["maximize"] * len(OBJECTIVES)
    stored = optuna.create_study(study_name=study_name(card, orientation), storage=storage, directions=directions, load_if_exists=True)
    work = optuna.create_study(study_name=study_name(card, orientation), directions=directions, sampler=sampler_of(sampler, seed, batch))
    work.add_trials(stored.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)))
    done = len(work.trials)
    batches = 0
    with tqdm(total=n_trials, initial=min(done, n_trials), desc=f"study {card}", unit="trial", disable=not progress) as bar:
        while done < n_trials and (stop_after is None or batches < stop_after):
            k = min(batch, n_trials - done)
            trials = [work.ask() for _ in range(k)]
            values = [suggest(t, card) for t in trials]
            ev = evaluate(card, {name: [v[name] for v in values] for name in values[0]}, grav=orientation[0], grav_dir=orientation[1])
            for i, t in enumerate(trials):
                for name, c in zip(CONSTRAINTS, ev.constraints[i]):
                    t.set_constraint(name, float(c))
                model = {key: val for key, val in ev.row(i).items() if key not in OBJECTIVES and not key.startswith("c_")}
                t.set_user_attr("model", model)
                t.set_user_attr("feasible", bool(ev.feasible[i]))
                t.set_user_attr("error", ev.error[i])
                work.tell(t, ev.objectives[i].tolist())
            everything = work.get_trials(deepcopy=False)
            stored.add_trials([everything[t.number] for t in trials])
            done += k
            batches += 1
            bar.update(k)
    return stored


def feasible_trials(study) -> list:
    from optuna.trial import TrialState

    return [t for t in study.get_trials(deepcopy=False, states=(TrialState.COMPLETE,)) if t.user_attrs.get("feasible")]


def design_of_trial(card: str, trial) -> Design:
    p = trial.params
    kw = {v.name: (int(p[v.name]) if v.name == "layers" else float(p[v.name])) for v in variables(card)}
    return Design(card=card, margin=MARGIN, **kw)


def pareto_mask(values: np.ndarray) -> np.ndarray:
    """Non-dominated rows of `values` (N, k), every column to maximise."""
    n = len(values)
    keep = np.ones(n, dtype=bool)
    order = np.argsort(-values[:, 0], kind="stable")
    v = values[order]
    for i in range(n):
        if not keep[order[i]]:
            continue
        # rows after i in the order have a first objective <= row i's
        dominated = np.all(v[i + 1 :] <= v[i], axis=1) & np.any(v[i + 1 :] < v[i], axis=1)
        keep[order[i + 1 :][dominated]] = False
    return keep


@dataclass
class Sweep:
    """The full grid of one card: how many candidates, how long, how many feasible, and the
    feasible candidates' designs and objectives (grip only for the non-dominated ones)."""

    card: str
    candidates: int
    seconds: float
    feasible: int
    evaluation: Evaluation

    @property
    def rate_per_min(self) -> float:
        return 60.0 * self.candidates / self.seconds


def grid_inputs(card: str, count: int = 7) -> Dict[str, np.ndarray]:
    """Every combination of `count` values per variable, as arrays by name."""
    vs = variables(card)
    axes = [np.asarray(v.grid(count)) for v in vs]
    mesh = np.meshgrid(*axes, indexing="ij")
    return {v.name: m.ravel() for v, m in zip(vs, mesh)}


def sweep(card: str, count: int = 7, *, chunk: int = 50_000, progress: bool = True, grip_front: bool = True, orientation: Tuple[float, float] = HORIZONTAL) -> Sweep:
    """Evaluate every grid point of `card` without the grip (the costly contact solve), then
    the grip of the feasible candidates non-dominated in the two stiffness ratios; each judged
    in `orientation` (grav, grav_dir)."""
    g = dict(grav=orientation[0], grav_dir=orientation[1])
    from tqdm import tqdm

    inputs = grid_inputs(card, count)
    n = len(next(iter(inputs.values())))
    keep: List[Dict[str, np.ndarray]] = []
    t0 = time.perf_counter()
    with tqdm(total=n, desc=f"sweep {card}", unit="cand", unit_scale=True, disable=not progress) as bar:
        for s in range(0, n, chunk):
            part = {k: v[s : s + chunk] for k, v in inputs.items()}
            ev = evaluate(card, part, grip=False, **g)
            idx = np.flatnonzero(ev.feasible)
            keep.append({k: v[idx] for k, v in part.items()})
            bar.update(len(part["t_min"]))
    seconds = time.perf_counter() - t0
    feas = {k: np.concatenate([e[k] for e in keep] or [np.zeros(0)]) for k in inputs}
    feas["margin"] = np.full(len(feas["t_min"]), MARGIN)
    count_feasible = len(feas["t_min"])
    if count_feasible and grip_front:
        ev = evaluate(card, feas, grip=False, **g)
        front = pareto_mask(ev.objectives[:, :2])
        idx = np.flatnonzero(front)
        ev = evaluate(card, {k: v[idx] for k, v in feas.items()}, grip=True, **g)
    else:
        ev = evaluate(card, feas, grip=False, **g) if count_feasible else None
    return Sweep(card=card, candidates=n, seconds=seconds, feasible=count_feasible, evaluation=ev)
