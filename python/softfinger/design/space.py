"""The design space: the variables a maker can build, with their ranges per film card, and one
design as a value (:class:`Design`) that reads and writes the TOML the firmware builds from
(``card`` plus the console's parameter names; docs/design.md).

Not here: what a design is worth (``evaluate``) or how the space is searched (``study``).
"""

from __future__ import annotations

import dataclasses
import math
import tomllib
from dataclasses import dataclass
from pathlib import Path
from typing import Dict, Optional, Sequence, Tuple

from .._core import BOARD_GRAV_DIR_DEG, BOARD_GRAV_M_S2

#: The films a board can be built with (docs/materials.md). ``paper-elastic`` is the paper's
#: modulus as printed, never a board's card, so it is not designed for.
CARDS: Tuple[str, ...] = ("VHB-4905", "Elastosil-2030")

#: The link thickness b of every design (the paper's finger, docs/model.md), mm: the notch depth
#: (b - t_min)/2 is what a stack must fit in.
LINK_B_MM = 10.0

#: The ceiling's margin, the board's: not a design variable (a safety factor is not traded
#: for stiffness).
MARGIN = 0.9


@dataclass(frozen=True)
class Variable:
    """One design variable: its console name, unit, the buildable range and the grid step (the
    resolution a build holds), or its choices; `why` says where the range comes from."""

    name: str
    unit: str
    low: float
    high: float
    step: Optional[float] = None
    choices: Optional[Tuple[float, ...]] = None
    log: bool = False
    integer: bool = False
    why: str = ""

    def grid(self, count: int = 7) -> Tuple[float, ...]:
        """`count` values spread over the range (the choices when there are fewer), each a
        buildable value (on the step)."""
        if self.choices is not None:
            if len(self.choices) <= count:
                return self.choices
            idx = [round(i * (len(self.choices) - 1) / (count - 1)) for i in range(count)]
            return tuple(self.choices[i] for i in sorted(set(idx)))
        if self.low == self.high:
            return (self.low,)
        out = []
        for i in range(count):
            u = i / (count - 1)
            v = math.exp(math.log(self.low) + u * (math.log(self.high) - math.log(self.low))) if self.log else self.low + u * (self.high - self.low)
            out.append(self.snap(v))
        return tuple(sorted(set(out)))

    def snap(self, v: float) -> float:
        """The nearest buildable value in range."""
        if self.choices is not None:
            return min(self.choices, key=lambda c: abs(c - v))
        v = min(max(v, self.low), self.high)
        if self.integer:
            return float(round(v))
        if self.step:
            v = self.low + round((v - self.low) / self.step) * self.step
            v = float(f"{v:.10g}")
        return v


# TPU grades: nominal Young's moduli across printable TPU (soft ~Shore 70A to ~Shore 98A), MPa;
# 12 MPa is docs/model.md's body. Nominal design points, not a datasheet's: a build measures its own.
TPU_GRADES_MPA: Tuple[float, ...] = (4.0, 6.0, 8.0, 12.0, 18.0, 26.0, 40.0)

_COMMON = (
    Variable("t_min", "mm", 0.5, 3.0, step=0.05, why="thinnest hinge section: 0.5 mm (a few printed perimeters) to 3 mm; must stay below b = 10 mm"),
    Variable("a", "mm", 2.5, 10.0, step=0.1, why="notch semi-axis: hinge length 2a from 5 to 20 mm inside the 27 mm pitch"),
    Variable("e_b", "MPa", 4.0, 40.0, choices=TPU_GRADES_MPA, why="body modulus: the TPU grades (nominal moduli, soft to stiff)"),
    Variable("w", "mm", 10.0, 30.0, step=0.5, why="finger width (the paper's 20 mm within 10-30 mm)"),
    Variable("layers", "1", 1, 40, integer=True, log=True, why="DE layers per stack; the stack must fit the notch (constraint `fits`)"),
)

#: The variables per card: the common ones, the film's layer thickness and the supply.
SPACE: Dict[str, Tuple[Variable, ...]] = {
    "VHB-4905": _COMMON
    + (
        Variable("z0", "mm", 0.5, 0.5, why="VHB 4905 is sold 0.5 mm thick (the card is the unstretched film)"),
        Variable("v_supply", "V", 1000.0, 20000.0, step=250.0, log=True, why="the HV module's full scale, 1-20 kV"),
    ),
    "Elastosil-2030": _COMMON
    + (
        Variable("z0", "mm", 0.02, 0.4, step=0.01, log=True, why="Elastosil Film 2030 is sold 20 to 400 um thick (docs/materials.md)"),
        Variable("v_supply", "V", 1000.0, 20000.0, step=250.0, log=True, why="the HV module's full scale, 1-20 kV"),
    ),
}

#: The TOML's keys besides `card`: the console's parameter names (docs/console.md), in order.
TOML_KEYS: Tuple[str, ...] = ("t_min", "a", "e_b", "w", "layers", "z0", "v_supply", "margin")
#: The finger's orientation (console names; issue 53), written after TOML_KEYS; a file without
#: them builds the board's (gravity on, hanging straight down).
ORIENTATION_KEYS: Tuple[str, ...] = ("grav", "grav_dir")


@dataclass(frozen=True)
class Design:
    """One design: a film card and the console's parameters (mm, MPa, V). Everything else is
    the default finger's (docs/model.md)."""

    card: str = "VHB-4905"
    t_min: float = 1.5
    a: float = 5.0
    e_b: float = 12.0
    w: float = 20.0
    layers: int = 4
    z0: float = 0.5
    v_supply: float = 10000.0
    margin: float = MARGIN
    #: the orientation the board built for it has (m/s², degrees): the board's by default
    grav: float = BOARD_GRAV_M_S2
    grav_dir: float = BOARD_GRAV_DIR_DEG
    #: the FE calibration factors computed for this design (``cal``'s 8, the console's order;
    #: ``fe.calibrate``), which the board built from it carries; None: uncalibrated
    cal: Optional[Tuple[float, ...]] = None

    def __post_init__(self):
        if self.cal is not None:
            object.__setattr__(self, "cal", tuple(float(g) for g in self.cal))

    def params(self) -> Dict[str, float]:
        """The design variables by console name (the study's inputs; ``orientation`` apart)."""
        return {k: float(getattr(self, k)) for k in TOML_KEYS}

    def orientation(self) -> Dict[str, float]:
        """``grav`` and ``grav_dir`` by console name."""
        return {k: float(getattr(self, k)) for k in ORIENTATION_KEYS}

    def finger(self):
        """The model of this design in its orientation, with the design's FE calibration
        (``cal``; uncalibrated without one): the model the board built from it runs."""
        from .. import Finger

        return Finger(preset="default", card=self.card, calibration=None if self.cal is None else list(self.cal), **self.params(), **self.orientation())

    def stack_mm(self) -> float:
        """The stack's thickness at rest, mm."""
        return self.layers * self.z0

    def to_toml(self, comment: str = "") -> str:
        """The design file (`designs/<card>.toml`, `FINGER_DESIGN=` for the firmware's build)."""
        lines = [f"# {l}" for l in comment.splitlines()] if comment else []
        lines.append(f'card = "{self.card}"')
        for k in TOML_KEYS + ORIENTATION_KEYS:
            v = getattr(self, k)
            lines.append(f"{k} = {int(v)}" if k == "layers" else f"{k} = {float(v)!r}")
        if self.cal is not None:
            lines.append("# FE calibration (h1 h2 h3 h4 ea0 ea1 ei0 ei1: the console's `cal`), computed for this design")
            lines.append("cal = [" + ", ".join(repr(float(g)) for g in self.cal) + "]")
        return "\n".join(lines) + "\n"

    @classmethod
    def from_toml(cls, text: "str | Path") -> "Design":
        """A design from its TOML text, or from a TOML file given as a :class:`pathlib.Path`
        (or a ``str`` that names an existing ``.toml`` file; :meth:`load` takes a path too);
        unknown keys or a missing one are an error (a typo must not build a default board)."""
        if isinstance(text, Path):
            return cls.load(text)
        if text.strip().endswith(".toml") and "\n" not in text.strip():
            if not Path(text.strip()).is_file():
                raise FileNotFoundError(f"design TOML: {text.strip()!r} looks like a path but is no file (from_toml takes TOML text or a path; Design.load(path) reads a file)")
            return cls.load(text.strip())
        try:
            d = tomllib.loads(text)
        except tomllib.TOMLDecodeError as e:
            raise ValueError(f"design TOML: not TOML text ({e}); from_toml takes TOML text or a path, Design.load(path) reads a file") from e
        want = {"card", *TOML_KEYS}
        extra, missing = set(d) - want - set(ORIENTATION_KEYS) - {"cal"}, want - set(d)
        if extra or missing:
            raise ValueError(
                f"design TOML: unknown keys {sorted(extra)}, missing {sorted(missing)}; keys: card, {', '.join(TOML_KEYS)} (optional: {', '.join(ORIENTATION_KEYS)}, cal)"
            )
        cal = d.get("cal")
        if cal is not None and not (isinstance(cal, list) and len(cal) == 8 and all(isinstance(g, (int, float)) and math.isfinite(g) for g in cal)):
            raise ValueError(f"design TOML: cal = {cal!r}: 8 finite numbers (h1 h2 h3 h4 ea0 ea1 ei0 ei1)")
        if d["card"] not in CARDS:
            raise ValueError(f"design TOML: card {d['card']!r}; cards: {', '.join(CARDS)}")
        if d["layers"] != int(d["layers"]):
            raise ValueError("design TOML: layers is an integer")
        for k, (lo, hi) in zip(ORIENTATION_KEYS, ((0.0, 20.0), (-180.0, 180.0))):
            if k in d and not (isinstance(d[k], (int, float)) and lo <= d[k] <= hi):
                raise ValueError(f"design TOML: {k} = {d[k]!r} is outside {lo:g}..{hi:g}")
        orientation = {k: float(d[k]) for k in ORIENTATION_KEYS if k in d}
        return cls(card=d["card"], **{k: (int(d[k]) if k == "layers" else float(d[k])) for k in TOML_KEYS}, **orientation, cal=None if cal is None else tuple(float(g) for g in cal))

    @classmethod
    def load(cls, path: Path | str) -> "Design":
        """A design from its TOML file."""
        return cls.from_toml(Path(path).read_text())

    def replace(self, **kw) -> "Design":
        return dataclasses.replace(self, **kw)


def variables(card: str) -> Tuple[Variable, ...]:
    """The design variables of `card`."""
    if card not in SPACE:
        raise ValueError(f"card {card!r}; cards: {', '.join(CARDS)}")
    return SPACE[card]


def grid_size(card: str, count: int = 7) -> int:
    """Candidates in the full grid of `count` values per variable."""
    return math.prod(len(v.grid(count)) for v in variables(card))


def design_of(card: str, values: Dict[str, float] | Sequence[float]) -> Design:
    """A design from variable values (by name, or in `variables(card)` order)."""
    if not isinstance(values, dict):
        values = dict(zip([v.name for v in variables(card)], values))
    kw = {k: (int(round(values[k])) if k == "layers" else float(values[k])) for k in values}
    return Design(card=card, margin=MARGIN, **kw)
