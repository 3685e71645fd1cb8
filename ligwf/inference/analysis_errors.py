"""Criteria on an error the analysis measured with its own interval (the GSD error and the
field criterion): the interval against the tolerance, ``pass`` when its upper end is within
it, ``fail`` when its lower end is above. The field criterion's interval is at the verdict's
alpha (:func:`ligwf.report.fields.add_field_errors`), its fail test's p-value and what would
decide it come from its noise pieces (:class:`~ligwf.inference.field_errors.LayerNoise`,
:func:`ligwf.inference.deciding.field_plan`); the GSD error's p-value reads its 95 %
bootstrap interval as a normal one.
"""

from __future__ import annotations

import math

from scipy import stats

from ligwf.inference import sampling
from ligwf.inference.deciding import decide_text
from ligwf.inference.equivalence import FAIL, PASS, UNDECIDED
from ligwf.inference.field_errors import FIELD_NOISE_COLUMNS, LayerNoise
from ligwf.inference.profile import replica_cost
from ligwf.inference.registry import (NOT_MEASURED, Criterion, CriterionResult, Decision,
                                      LevelData, band, row_value)

#: z_0.975: the GSD error's bootstrap interval is a 95 % one
Z_95 = 1.959963984540054


def decide_error(spec: Criterion, tolerance: float, level: LevelData) -> Decision:
    """An analysis error on one level; its fail test's p-value from its interval read as a
    normal one (se = width / 2 z_0.975), an approximation: a bootstrap gives no p-value."""
    if level.row is None or spec.metric not in level.row.index:
        return Decision(CriterionResult(**spec.base(), state=NOT_MEASURED, note=(
            f"not measured: the study has no {spec.metric}")))
    r = interval_result(spec, tolerance, level)
    return Decision(r, normal_fail_p(r, tolerance))


def decide_field(spec: Criterion, tolerance: float, level: LevelData) -> Decision:
    """The field criterion on one level: its fail test's p-value from its noise pieces
    (:meth:`LayerNoise.fail_p`, the test its bounds make), else as :func:`decide_error`."""
    decision = decide_error(spec, tolerance, level)
    r = decision.result
    if not (r.assessed and math.isfinite(r.lo) and math.isfinite(r.hi)):
        return decision
    values = [row_value(level.row, c) for c in FIELD_NOISE_COLUMNS]
    if all(math.isfinite(v) for v in values):
        return Decision(r, LayerNoise(values[0], values[1], values[2], int(values[3]),
                                      int(values[4])).fail_p(tolerance))
    return decision


def normal_fail_p(r: CriterionResult, tolerance: float) -> float:
    """The fail test's p-value of an interval read as a normal 95 % one (nan: not tested)."""
    if not (r.assessed and math.isfinite(r.lo) and math.isfinite(r.hi)):
        return math.nan
    se = (r.hi - r.lo) / (2.0 * Z_95)
    if not se > 0:
        return 0.0 if r.value > tolerance else 1.0
    return float(stats.norm.sf((r.value - tolerance) / se))


def interval_result(spec: Criterion, tolerance: float, level: LevelData) -> CriterionResult:
    """The analysis' interval against the tolerance, with what would decide it (the
    criterion's ``plan``, given the condition row, the tolerance, alpha and the core-seconds
    of a replica of each arm)."""
    base = spec.base(tolerance)
    value, lo, hi = band(level.row, spec.metric)
    if not math.isfinite(value):
        return CriterionResult(**base, state=NOT_MEASURED,
                               note=f"not measured: no {spec.metric} value for this condition")
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return CriterionResult(**base, state=UNDECIDED, value=value,
                               note="no interval (add replicas)")
    state = PASS if hi <= tolerance else FAIL if lo > tolerance else UNDECIDED
    decide = {}
    if state == UNDECIDED and spec.plan is not None:
        costs = (replica_cost(level.runs, level.noise),
                 replica_cost(level.ref_runs, level.noise))
        decide = spec.plan(level.row, tolerance, level.alpha, costs)
    note = ""
    if state == UNDECIDED:
        how = decide_text(CriterionResult(**base, state=state, **decide))
        note = how or (f"over {sampling.MOST_REPLICAS} replicas of an arm would be needed"
                       if decide else "more replicas of both arms")
    return CriterionResult(**base, state=state, value=value, lo=lo, hi=hi, bound=hi,
                           note=note, **decide)
