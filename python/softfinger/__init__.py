"""softfinger: the variable-stiffness soft finger from Python.

- :class:`Finger`: the model (the Rust crate ``finger-model`` in f64, no second implementation):
  ``solve``, ``solve_many`` (parallel, GIL released), ``pose`` (the inverse), ``contact``,
  ``fmax``, ``ceiling``. Results are NumPy arrays; units in the names (``_mm``, ``_N``, ``_V``,
  ``_rad``, ``_deg``) or the docstrings.
- :class:`Board`: a driver board over its serial console (pyserial), the simulated board
  (``Board.sim()``) or the firmware's emulator image (``Board.qemu()``).
- :mod:`softfinger.errors`: the model's refusals as exceptions (:class:`FingerError` and
  subclasses); :class:`BoardError` for a board's ``err`` replies.

Units: lengths mm, forces N, moments N·mm, moduli MPa, voltages V, angles rad (degrees only where
a name says so, and at the board's console).
"""

from ._core import BranchLimit, Contact, Finger, PoseSolution, Solution, Solutions, cards, parameter_ranges
from .board import Board, BoardError, BoardLinkError, BoardSolution, BoardTimeout, Force, Limits, Pose, Status
from .errors import (
    BranchEndError,
    FingerError,
    InputError,
    NotConvergedError,
    ThicknessLimitError,
    UnreachableError,
    VoltageCeilingError,
)

__all__ = [
    "Finger",
    "Solution",
    "Solutions",
    "PoseSolution",
    "Contact",
    "BranchLimit",
    "parameter_ranges",
    "cards",
    "Board",
    "BoardError",
    "BoardTimeout",
    "BoardLinkError",
    "Status",
    "Limits",
    "BoardSolution",
    "Force",
    "Pose",
    "FingerError",
    "VoltageCeilingError",
    "ThicknessLimitError",
    "UnreachableError",
    "NotConvergedError",
    "InputError",
    "BranchEndError",
]
