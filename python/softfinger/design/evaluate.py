"""What a design is worth and whether it may be built: the objectives and the constraints of
the design study, from one batched model call (``_core.evaluate_designs``: Rust, parallel, GIL
released) over many candidates of one card.

Objectives (larger is better):

- ``ratio_kyy``, ``ratio_ktt``: the tip stiffness k_yy (N/mm) and k_θθ (N·mm/rad), max over
  min, at the reference posture held by the inverse across the feasible voltages: the two ends
  of its tension interval, one joint at the top voltage the ceiling allows and the joints at
  0 V (``inverse::stiffness_range``). The reference posture: every joint at 10° without
  gravity; under the finger's weight (the study's ``HORIZONTAL``) the 0 V posture with the same
  tip angle (30°), at the tension that gives it: the weight loads the joints unequally, and no
  design holds every joint at 10° horizontally (a design whose weight alone bends it past that
  tip angle, or that no tension brings there, is refused at the stage ``reference``);
- ``grip_N``: the grip force at fmax: the tip stopped where the posture's 0 V end puts it, the
  cable pulled to fmax (``contact``), |F| in N.

Constraints (feasible when every value is <= 0; each is a number the model computed):

- ``refused``: 1 when the model refused the design at any step (its typed error: a parameter
  out of range, an unreachable posture, a branch end, ...), else 0;
- ``ceiling``: the highest voltage used over the ceiling, minus 1 (the card's hold ceiling
  with the margin, capped by the supply);
- ``breakdown``: the highest field across a layer at its thinned thickness over the card's
  breakdown field, minus 1;
- ``thinning``: 2/3 minus the thinnest stack's thickness stretch (the 33 % limit);
- ``fmax``: (floor - fmax) / floor, fmax the lower of the two ends';
- ``fits``: the stack's thickness over the notch depth (b - t_min)/2, minus 1 (geometry: the
  stack lies in the notch, as the FE mesh builds it).

Not here: the search (``study``), the FE check (``fe``).
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Dict, List, Sequence

import numpy as np

from .. import _core
from .space import LINK_B_MM, Design, TOML_KEYS

OBJECTIVES = ("ratio_kyy", "ratio_ktt", "grip_N")
CONSTRAINTS = ("refused", "ceiling", "breakdown", "thinning", "fmax", "fits")
#: The reference posture: every joint at this angle, degrees (docs/inverse-tables.md's).
REFERENCE_DEG = 10.0
#: The fmax floor, N: the finger must pull at least this much before its branch ends.
FMAX_FLOOR_N = 2.0
#: The orientation the study judges a design in (m/s², degrees; issue 55): held horizontally,
#: the weight bending the finger the way the cable does (``grav_dir`` 90), where a soft finger
#: sags: the reference posture must be held under the finger's own weight.
HORIZONTAL = (9.81, 90.0)


@dataclass
class Evaluation:
    """Arrays over N candidates of one card: `objectives` (N, 3) and `constraints` (N, 6) in the
    order of OBJECTIVES and CONSTRAINTS, `feasible` (N,), `error` (N,) the model's refusal as
    "stage:Kind" ("" when it solved), and `raw` the model's outputs (``evaluate_designs``)."""

    card: str
    inputs: Dict[str, np.ndarray]
    objectives: np.ndarray
    constraints: np.ndarray
    feasible: np.ndarray
    error: List[str]
    raw: Dict[str, np.ndarray]

    def __len__(self) -> int:
        return len(self.feasible)

    def design(self, i: int) -> Design:
        return Design(card=self.card, **{k: (int(self.inputs[k][i]) if k == "layers" else float(self.inputs[k][i])) for k in TOML_KEYS})

    def row(self, i: int) -> Dict[str, float]:
        """Candidate i's objectives, constraints and model outputs by name (plain floats)."""
        r = self.raw
        out = {k: float(v) for k, v in zip(OBJECTIVES, self.objectives[i])}
        out.update({f"c_{k}": float(v) for k, v in zip(CONSTRAINTS, self.constraints[i])})
        out.update(
            ceiling_V=float(r["ceiling_V"][i]),
            tension_lo_N=float(r["tension_N"][i, 0]),
            tension_hi_N=float(r["tension_N"][i, 1]),
            kyy_lo=float(r["kyy"][i, 0]),
            kyy_hi=float(r["kyy"][i, 1]),
            ktt_lo=float(r["ktt"][i, 0]),
            ktt_hi=float(r["ktt"][i, 1]),
            volts_top_V=float(r["volts_top_V"][i]),
            s_min=float(r["s_min"][i]),
            field_V_per_um=float(r["field_V_per_um"][i]),
            fmax_N=float(r["fmax_N"][i]),
        )
        return out


def _ratio(k: np.ndarray) -> np.ndarray:
    lo, hi = np.minimum(k[:, 0], k[:, 1]), np.maximum(k[:, 0], k[:, 1])
    return np.where(lo > 0, hi / np.where(lo > 0, lo, 1.0), 1.0)


def evaluate(card: str, inputs: Dict[str, Sequence[float]] | Sequence[Design], *, grip: bool = True, fmax_floor_N: float = FMAX_FLOOR_N, reference_deg: float = REFERENCE_DEG, grav: float = 0.0, grav_dir: float = 0.0) -> Evaluation:
    """Evaluate candidates of `card`: a dict of arrays by console name (t_min, a, e_b, w,
    layers, z0, v_supply; margin optional) or a sequence of Designs. `grip=False` skips the
    grip force (the costly part: about 25x the rest) and leaves that objective 0. `grav` (m/s²)
    and `grav_dir` (degrees): the orientation every candidate is judged in (default: none, the
    study's so far; a Design's own `grav`/`grav_dir` is the board it builds). Under gravity
    without the grip, `fmax_N` is the floor for a finger that holds it at both ends (the exact
    fmax there is a bisection of coupled solves, hundreds of ms; the constraint needs only
    fmax >= floor)."""
    if not isinstance(inputs, dict):
        designs = list(inputs)
        if any(d.card != card for d in designs):
            raise ValueError("every design on the card evaluated")
        inputs = {k: [getattr(d, k) for d in designs] for k in TOML_KEYS}
    cols = {k: np.atleast_1d(np.asarray(inputs[k], dtype=float)) for k in TOML_KEYS if k in inputs}
    n = max(len(v) for v in cols.values())
    cols = {k: np.broadcast_to(v, (n,)).copy() for k, v in cols.items()}
    if "margin" not in cols:
        from .space import MARGIN

        cols["margin"] = np.full(n, MARGIN)
    r = _core.evaluate_designs(card, cols["t_min"], cols["a"], cols["e_b"], cols["w"], cols["layers"], cols["z0"], cols["v_supply"], margin=cols["margin"], angle_deg=reference_deg, grip=grip, grav=grav, grav_dir=grav_dir, fmax_floor=fmax_floor_N)
    kind, stage = r["kind"].astype(int), r["stage"].astype(int)
    refused = kind != 0
    solved = ~refused
    ratio_kyy, ratio_ktt = _ratio(r["kyy"]), _ratio(r["ktt"])
    grip_n = r["grip_N"]
    objectives = np.stack([np.where(solved, ratio_kyy, 1.0), np.where(solved, ratio_ktt, 1.0), np.where(solved, grip_n, 0.0)], axis=1)
    depth = (LINK_B_MM - cols["t_min"]) / 2.0
    # a refused design's model outputs are zeros: its model constraints say only "refused"
    safe = lambda x: np.where(refused, 0.0, x)
    ceiling = r["ceiling_V"]
    constraints = np.stack(
        [
            refused.astype(float),
            safe(r["volts_top_V"] / np.where(ceiling > 0, ceiling, 1.0) - 1.0),
            safe(r["field_V_per_um"] / r["breakdown_V_per_um"] - 1.0),
            safe(2.0 / 3.0 - r["s_min"]),
            safe((fmax_floor_N - r["fmax_N"]) / fmax_floor_N),
            np.where(depth > 0, cols["layers"] * cols["z0"] / np.where(depth > 0, depth, 1.0) - 1.0, 1.0),
        ],
        axis=1,
    )
    # strictly below the ceiling: the model refuses at it
    feasible = np.all(constraints <= 0.0, axis=1) & (constraints[:, 1] < 0.0)
    kinds, stages = r["error_kinds"], r["stages"]
    error = [f"{stages[s]}:{kinds[k]}" if k else "" for k, s in zip(kind, stage)]
    return Evaluation(card=card, inputs=cols, objectives=objectives, constraints=constraints, feasible=feasible, error=error, raw=r)
