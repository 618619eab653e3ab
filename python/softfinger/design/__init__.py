"""softfinger.design: which finger of this kind varies its stiffness most inside its HV safety
bounds (docs/design.md).

- :mod:`.space`: the design variables with their buildable ranges per film card, and
  :class:`Design` (one design; its TOML is what the firmware builds from);
- :mod:`.evaluate`: the objectives (stiffness ratios, grip force) and the constraints (the
  card's ceiling, breakdown, the 33 % limit, the reference posture, the fmax floor, the stack's
  fit), from one batched model call;
- :mod:`.study`: Optuna's multi-objective search, resumable, and the exhaustive grid sweep;
- :mod:`.fe`: the Pareto designs checked by CalculiX, as tasks on a Dask cluster;
- :mod:`.report`: docs/design.md, its figures and designs/<card>.toml.

Command line: ``python -m softfinger.design --help``.
"""

from .evaluate import CONSTRAINTS, OBJECTIVES, Evaluation, evaluate
from .space import CARDS, SPACE, Design, Variable, variables
from .study import pareto_mask, run_study, storage_of, sweep

__all__ = ["CARDS", "SPACE", "Design", "Variable", "variables", "OBJECTIVES", "CONSTRAINTS", "Evaluation", "evaluate", "run_study", "storage_of", "sweep", "pareto_mask"]
