"""The model's typed errors, as Python exceptions.

Every refusal of the model (``finger_model::Error``) is raised as one of these, carrying the
error's fields by name (units as in the field names: V, mm, N), plus:

- ``kind``: the model's variant (``"VoltageCeiling"``, ``"ThicknessLimit"``, ...);
- ``code``: the console's error code for it (``"limit"``, ``"unreachable"``, ``"fault"``, ...);
- ``index``: for ``Finger.solve_many``, the row that failed;
- ``fields``: the variant's fields as a dict.

The model never returns NaN or infinity as a result; a refused request raises instead.
"""

from __future__ import annotations

from typing import Any, Dict, Optional


class FingerError(Exception):
    """Base of every model refusal (also the class of ``Singular``: a singular system; and of
    ``PullingStop``: ``contact``'s stop would pull on the tip, fields ``tension`` N and
    ``force``, N along the tip's approach)."""

    kind: str
    code: str
    index: Optional[int]
    fields: Dict[str, Any]

    def __init__(self, message: str, *, kind: str = "", code: str = "fault", index: Optional[int] = None, **fields: Any):
        super().__init__(message)
        self.kind = kind
        self.code = code
        self.index = index
        self.fields = dict(fields)
        for k, v in fields.items():
            setattr(self, k, v)


class VoltageCeilingError(FingerError):
    """A channel voltage at or past its ceiling (the film's hold ceiling with its margin,
    capped by v_supply), or a film driven past its pull-in.

    Fields: ``joint`` (1-based), ``volts`` (V), ``ceiling`` (V); for a pull-in (kind
    ``PullIn``): ``volts``, ``pull_in`` (V)."""


class ThicknessLimitError(FingerError):
    """A stack thickness past the 33 % pull-in limit (z < 2/3 z0), e.g. the paper's "2 mm to 1 mm".

    Fields: ``joint`` (1-based), ``requested_mm``, ``limit_mm``."""


class UnreachableError(FingerError):
    """A posture the inverse cannot hold within the ceiling.

    Fields: ``joint`` (1-based), ``needed`` (the compliance it would need, rad/(N·mm)),
    ``min``, ``max`` (the range the ceiling allows, rad/(N·mm))."""


class NotConvergedError(FingerError):
    """The solver did not reach its tolerance.

    Fields: ``iterations``, ``residual`` (mm; infinite when the solver stopped before measuring it)."""


class InputError(FingerError, ValueError):
    """A parameter out of its range (kind ``Param``: ``name``, ``range``), an input not finite
    (``NonFinite``: ``input``) or outside its domain (``Input``: ``input``, ``reason``)."""


class BranchEndError(FingerError):
    """The equilibrium branch ends before the request: the links touch (``Contact``: ``joint``,
    ``tension`` N), a limit point (``LimitPoint``: ``joint``, ``tension`` N), or a tension past
    fmax (``ForceLimit``: ``tension``, ``fmax``, N)."""


__all__ = [
    "FingerError",
    "VoltageCeilingError",
    "ThicknessLimitError",
    "UnreachableError",
    "NotConvergedError",
    "InputError",
    "BranchEndError",
]
