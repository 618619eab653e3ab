"""Type stubs of the native module (Rust, PyO3): the model. Units in the names or the docs:
lengths mm, forces N, moments N·mm, voltages V, angles rad (``_deg``: degrees)."""

from typing import Dict, List, Literal, Optional, Sequence, Tuple, Union

import numpy as np
import numpy.typing as npt

from .errors import FingerError

F64 = npt.NDArray[np.float64]
ArrayLike = Union[float, Sequence[float], npt.NDArray[np.floating]]
Method = Literal["converged", "stepping"]

class Solution:
    """A solved posture. Every array is a fresh copy."""

    @property
    def n(self) -> int:
        """Number of joints."""
    @property
    def tension_N(self) -> float:
        """Cable tension P, N."""
    @property
    def volts_V(self) -> F64:
        """Channel voltages, V, shape (n,)."""
    @property
    def joints_rad(self) -> F64:
        """Joint angles Δθ_k, rad, shape (n,)."""
    @property
    def joints_deg(self) -> F64:
        """Joint angles, degrees, shape (n,)."""
    @property
    def nodes(self) -> F64:
        """Node poses 0..n, shape (n+1, 3): x mm, y mm, θ rad (base frame; the last is the tip)."""
    @property
    def tip(self) -> F64:
        """Tip pose, shape (3,): x mm, y mm, θ rad."""
    @property
    def cable_mm(self) -> float:
        """Cable excursion the servo pulls in, Σ (L_h − |span k|), mm."""
    @property
    def thickness_mm(self) -> F64:
        """Whole-stack thickness per joint, mm, shape (n,) (0 without stacks)."""
    @property
    def stiffness(self) -> Optional[F64]:
        """Tip stiffness K_tip, shape (3, 3), rows/columns (x mm, y mm, θ rad): N/mm, N/rad,
        N·mm/rad; None when solved with ``stiffness=False``."""
    @property
    def iterations(self) -> int:
        """Newton iterations (converged) or load steps (stepping)."""
    @property
    def residual_mm(self) -> float:
        """Final equilibrium residual (guide-hole mismatch), mm."""

class Solutions:
    """``solve_many``'s answers; the first axis of every array is the posture (N). A refused
    row (``errors="mask"``) holds NaN in every result (its asked tension and voltages kept), ``ok`` False, and its exception in ``errors``."""

    tension_N: F64
    """(N,), N."""
    volts_V: F64
    """(N, n), V."""
    joints_rad: F64
    """(N, n), rad."""
    nodes: F64
    """(N, n+1, 3): x mm, y mm, θ rad."""
    tip: F64
    """(N, 3): x mm, y mm, θ rad."""
    cable_mm: F64
    """(N,), mm."""
    thickness_mm: F64
    """(N, n), mm."""
    stiffness: Optional[F64]
    """(N, 3, 3): N/mm, N/rad, N·mm/rad; None with ``stiffness=False``."""
    iterations: npt.NDArray[np.uint32]
    """(N,)."""
    residual_mm: F64
    """(N,), mm."""
    ok: npt.NDArray[np.bool_]
    """(N,): the row solved."""
    errors: List[Tuple[int, FingerError]]
    """(row, exception) of every refused row (``errors="mask"``)."""
    @property
    def joints_deg(self) -> F64:
        """(N, n), degrees."""
    def __len__(self) -> int: ...

class PoseSolution:
    """The inverse model's answer."""

    @property
    def angles_rad(self) -> F64:
        """The target joint angles, rad, shape (n,)."""
    @property
    def tension_N(self) -> float:
        """The cable tension, N (given, or the midpoint of ``interval_N``)."""
    @property
    def tension_given(self) -> bool: ...
    @property
    def volts_V(self) -> F64:
        """Channel voltages that hold the posture, V, shape (n,)."""
    @property
    def thickness_mm(self) -> F64:
        """Stack thickness per joint, mm, shape (n,)."""
    @property
    def interval_N(self) -> F64:
        """The feasible interval of tensions [low, high], N."""
    @property
    def solution(self) -> Solution:
        """The posture as a forward solution, with its tip stiffness."""
    @property
    def iterations(self) -> int: ...

class Contact:
    """The contact force of a tip held at a point."""

    @property
    def point_mm(self) -> F64:
        """The contact point (the free tip at P0), mm, shape (2,)."""
    @property
    def force_N(self) -> F64:
        """The force the object exerts on the tip, N, shape (2,); the finger presses with −force."""
    @property
    def force_on_tip_N(self) -> F64:
        """``force_N`` by the name of its sign: the stop's force on the tip, N, shape (2,) (the
        console's ``force_on_tip``; its ``fx``, ``fy`` are the opposite)."""
    @property
    def magnitude_N(self) -> float: ...
    @property
    def solution(self) -> Solution:
        """The loaded equilibrium holding the tip at the point."""
    @property
    def iterations(self) -> int: ...

class BranchLimit:
    """Where the equilibrium branch ends."""

    tension_N: float
    """N."""
    joint: int
    """1-based joint where it ends first."""
    kind: Literal["contact", "limit-point", "search-bound"]
    def __float__(self) -> float: ...

class Finger:
    """The finger's model, prepared once: parameters validated, hinge compliances computed.

    ``preset``: ``"board"`` (the default: the board's finger, docs/model.md's geometry on the
    board's film VHB 4905 with the board's FE calibration and hold ceiling: what the board's
    ``solve`` answers), ``"default"`` (docs/model.md's finger on its default film, m = 8, plate
    modulus, flexible links), ``"paper"`` (the paper's model and its Eq. 3 DE modulus) or
    ``"paper_model"`` (the paper's model with the corrected DE modulus). ``calibration``:
    ``"auto"`` (the default: the board's FE calibration on the board's finger, none on the other
    presets), ``"model_md"`` (docs/model.md's FE factors), None (none) or 8 factors; a
    calibration that does not apply to the finger raises :class:`InputError` (never dropped).
    ``**params``: any parameter by its console name (``l``, ``b``, ``w``, ``t_min``, ``a``,
    ``e_b``, ``e``, ``layers``, ``z0``, ``g``, ``nu``, ``eps_r``, ``margin``, ``v_supply``,
    ``n_inc``, ``m``, ``plate``, ``nu_b``, ``span_floor``, ``flex_links``; mm, MPa, V; gravity:
    ``grav`` m/s² 0..20 (0: off), ``grav_dir`` degrees -180..180 from the straight finger's axis
    toward the cable side (0 hanging straight down, 90 held horizontally curling downward, -90
    curling upward), ``rho_b`` the body's density g/cm³). Raises :class:`InputError` naming the
    parameter for a value out of range. The board's finger (``"board"``) hangs straight down
    under 9.81 m/s², as the board's; the other presets have no gravity. ``card``: the DE film's material card
    (:func:`cards`, e.g. ``"VHB-4905"``; docs/materials.md) on the preset's finger: its
    equilibrium modulus (``g``) and permittivity (``eps_r``), its breakdown field in the
    ceiling; default the preset's. The repr names preset, card, calibration and ceiling."""

    def __init__(self, preset: Literal["board", "default", "paper", "paper_model"] = "board",
                 calibration: Union[None, str, Sequence[float]] = "auto", card: Optional[str] = None,
                 **params: float) -> None: ...
    @property
    def preset(self) -> str:
        """The preset the finger started from."""
    @property
    def card(self) -> str:
        """The film's material card."""
    @property
    def params(self) -> dict[str, float]:
        """Every parameter by its console name (``e_de`` derived, MPa)."""
    @property
    def calibration(self) -> List[float]:
        """hinge ×4, stack EA (g0, g1 /mm), stack EI (g0, g1 /mm)."""
    @property
    def n(self) -> int: ...
    def ceiling(self) -> float:
        """The voltage every channel stays below: min(margin × V_pi, v_supply) and, on the
        board's finger, the board's hold ceiling, V."""
    def pull_in_voltage(self) -> float:
        """V_pi of one layer (the 33 % limit), V."""
    def stack_thickness(self, volts: float) -> float:
        """Whole-stack thickness at ``volts`` V, mm."""
    def volts_for_thickness(self, thickness_mm: ArrayLike) -> F64:
        """Channel voltages (V) that thin the stacks to ``thickness_mm`` (mm per joint or one
        number); :class:`ThicknessLimitError` past the 33 % limit."""
    def solve(self, P: float, volts: ArrayLike, *, method: Method = "converged", n_inc: Optional[int] = None,
              tol: float = 1e-9, max_iter: int = 200, stiffness: bool = True) -> Solution:
        """The posture at cable tension ``P`` (N) and channel voltages ``volts`` (V, n values or
        one). ``tol`` mm; ``method="stepping"``: the paper's load stepping, ``n_inc`` steps."""
    def solve_many(self, P: ArrayLike, volts: ArrayLike, *, grav_dir: Optional[ArrayLike] = None,
                   method: Method = "converged", n_inc: Optional[int] = None,
                   tol: float = 1e-9, max_iter: int = 200, stiffness: bool = True,
                   errors: Literal["raise", "mask"] = "raise") -> Solutions:
        """``solve`` over N postures in parallel (GIL released): ``P`` (N,) or one number, N;
        ``volts`` (N, n), (n,) or one number, V; ``grav_dir`` (N,) or one number, degrees: the
        finger's orientation per posture (None: the finger's own ``grav_dir``; out of range
        raises :class:`InputError` naming it). ``errors="raise"``: the first refused row's
        exception (its ``index``); ``"mask"``: see :class:`Solutions`."""
    def pose(self, angles: ArrayLike, P: Optional[float] = None, *, degrees: bool = False) -> PoseSolution:
        """The inverse: joint angles (rad; degrees with ``degrees=True``) and optionally the
        tension ``P`` (N) to the tension and voltages that hold them, with the feasible interval."""
    def contact(self, P0: float, P: float, volts: ArrayLike, volts0: Optional[ArrayLike] = None) -> Contact:
        """The tip stops at the free tip of (``P0`` N, ``volts0`` V, default ``volts``); at ``P``
        and ``volts`` the force that holds it there."""
    def fmax(self, volts: ArrayLike) -> BranchLimit:
        """The tension (N) where the equilibrium branch ends at ``volts`` (V)."""

def cards() -> List[str]:
    """Every material card's name (``Finger(card=...)``)."""

BOARD_GRAV_M_S2: float
"""The board's finger's gravity, m/s² (9.81: on; ``Finger()``'s ``grav``)."""
BOARD_GRAV_DIR_DEG: float
"""The board's finger's orientation, degrees (0: hanging straight down)."""

def parameter_ranges() -> List[Tuple[str, str]]:
    """Every parameter name with its valid range, as the console states them."""

# A board's reply lines, read by the console protocol crate (softfinger/board.py's parser).
def _reply_final(line: str) -> Optional[Tuple[str, ...]]:
    """``("ok",)``, ``("err", code, message)``, or None for a line before a final one."""

def _reply_fields(line: str) -> Dict[str, Union[float, str, Tuple[float, ...]]]:
    """The ``key=value`` fields of a line: floats, tuples of floats, else the text."""

def _reply_measured(line: str, key: str) -> Optional[List[float]]:
    """``key``'s numbers, ``-`` as NaN; None without ``key`` or with a word in it."""
