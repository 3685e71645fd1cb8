"""A toy criterion that lives in the test folder, as ``tests/toy_constant.py`` is a toy
liquid: the largest distance of a CG-n run's angle of repose from the CG1 runs' mean, held
within its own ``accept:`` key ``toy_spread_deg``. It is one module: its decision and its
declaration; :func:`ligwf.inference.registry.register` does the rest (the ``accept:`` key,
the verdict, its record, the report's verdict table, the data dictionary)."""

from __future__ import annotations

import numpy as np

from ligwf.inference.equivalence import FAIL, PASS
from ligwf.inference.registry import (ERROR, NOT_MEASURED, Criterion, CriterionResult, Decision,
                                      LevelData)
from ligwf.inference.signed import per_run
from ligwf.scene.accept import Budget

BUDGET = Budget("toy_spread_deg", 3.0, 90.0,
                "largest |CG-n run - CG1 mean| of the angle of repose, deg (a toy)")


def decide_spread(spec: Criterion, tolerance: float, level: LevelData) -> Decision:
    """Pass when no CG-n run is further than the tolerance from the CG1 mean, else fail
    (a deterministic toy: its fail test's p-value is 0 or 1)."""
    x, y = per_run(level.runs, spec.metric), per_run(level.ref_runs, spec.metric)
    if not (len(x) and len(y)):
        return Decision(CriterionResult(**spec.base(tolerance), state=NOT_MEASURED,
                                        note="not measured: an arm has no runs"))
    spread = float(np.max(np.abs(x - np.mean(y))))
    state = PASS if spread <= tolerance else FAIL
    return Decision(CriterionResult(**spec.base(tolerance), state=state, value=spread,
                                    lo=spread, hi=spread, bound=spread),
                    p_fail=0.0 if state == FAIL else 1.0)


TOY = Criterion("toy_spread_deg", "toy run spread", "deg", "angle_of_repose", ERROR,
                decide_spread, budget=BUDGET)
