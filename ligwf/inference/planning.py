"""What the verdict needs to cost "what would decide": per run its noise and its prices.

Per usable case (one row, indexed by case id):

* for every signed criterion's column, the within-run variance of the run's value from its
  own steady-window frames (:func:`ligwf.inference.sampling.within_variance`; a
  share of frames above a threshold is the mean of its 0/1 series);
* ``window_seconds``: the steady window's length (frames x their spacing, s) and
  ``steady_share``: the share of added production that would be steady window (1 - the
  run's steady fraction: the window is a fraction of the production time);
* ``steady_at_cap``: the window starts at its cap (``steady_after: auto`` found no steady
  start in the first half: the run is too short) and ``least_extension_seconds``: the
  production to add to each run so its truncation is at most a quarter of production (both
  :mod:`ligwf.analysis.records.steady_window`; 0 for a fixed ``steady_after``, whose window
  is a fixed share of any production);
* ``replica_core_seconds``: a new replica from its fill to its end, and
  ``production_core_seconds``: one simulated second of production, both on one rank from
  the planner's measured rates (:func:`ligwf.engine.plan.estimated_seconds`) times what
  this machine did: measured over planned core-seconds of the fastest finished run of the
  case's condition (:func:`calibration`; 1 without one).

Pure given its inputs (the study's case folders and its flow record).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np
import pandas as pd

from ligwf.analysis.records import steady_window as steady
from ligwf.analysis.records.flow import FlowRecord
from ligwf.inference.sampling import within_variance
from ligwf.analysis.records.statistics import MEAN, SHARE_ABOVE
from ligwf.engine.plan import case_load, estimated_seconds
from ligwf.scene.scaled import ScaledScene
from ligwf.study.case import CaseFolder
from ligwf.study.condition import Condition

#: the columns of a noise table besides the per-criterion within-run variances
WINDOW, STEADY_SHARE = "window_seconds", "steady_share"
REPLICA_COST, PRODUCTION_COST = "replica_core_seconds", "production_core_seconds"
AT_CAP, LEAST_EXTENSION = "steady_at_cap", "least_extension_seconds"


def within_column(column: str) -> str:
    """The noise table's column of a criterion column's within-run variance."""
    return f"{column}_within_var"


def run_costs(scaled: ScaledScene) -> tuple[float, float]:
    """(core-seconds of a whole new replica, core-seconds per simulated second of
    production) of a case on one rank, from the planner's rates."""
    load = case_load("cost", scaled)
    replica = estimated_seconds(load, 1)
    steps_per_second = max(1, round(1.0 / scaled.numerics.dt))
    production = estimated_seconds(dataclasses.replace(load, steps=steps_per_second), 1)
    return replica, production


def _series_value_noise(flow: FlowRecord, case_id: str, column: str) -> float:
    c = flow.cases.get(case_id)
    try:
        spec = flow.metric(column)
    except StopIteration:
        return math.nan
    if c is None or spec.series not in c.series:
        return math.nan
    x = np.array([np.nan if v is None else v for v in c.series[spec.series]], dtype=float)
    if x.ndim != 1:
        return math.nan
    if spec.statistic == SHARE_ABOVE:
        return within_variance(np.where(np.isfinite(x), (x > spec.threshold).astype(float),
                                        np.nan))
    if spec.statistic == MEAN:
        return within_variance(x)
    return math.nan


def _window_seconds(flow: FlowRecord, case_id: str) -> float:
    c = flow.cases.get(case_id)
    if c is None or len(c.times) < 2:
        return math.nan
    t = np.sort(np.asarray(c.times, float))
    return float(len(t) * np.median(np.diff(t)))


def calibration(cases: list[CaseFolder]) -> float:
    """Measured over planned core-seconds of the fastest finished run among ``cases`` (1
    without one): the planner's rates scaled to what this machine did; the fastest, so that
    a run slowed by a shared machine or a retry does not inflate the prices."""
    ratios = []
    for c in cases:
        m = c.manifest()
        planned = run_costs(c.scaled)[0]
        if m is not None and m.core_seconds > 0 and planned > 0:
            ratios.append(m.core_seconds / planned)
    return min(ratios) if ratios else 1.0


def noise_table(cases: list[CaseFolder], flow: FlowRecord, columns: tuple[str, ...]
                ) -> pd.DataFrame:
    """The noise and prices of every case (see the module docstring), indexed by case id."""
    rows = []
    arms: dict[Condition, list[CaseFolder]] = {}
    for case in cases:
        arms.setdefault(case.condition, []).append(case)
    rate = {condition: calibration(arm) for condition, arm in arms.items()}
    for case in cases:
        replica, production = (rate[case.condition] * x for x in run_costs(case.scaled))
        c = flow.cases.get(case.case_id)
        share = 1.0 - float(c.steady_fraction) if c is not None else math.nan
        fraction = float(c.steady_fraction) if c is not None else math.nan
        production_time = case.scaled.numerics.run_steps * case.scaled.numerics.dt
        auto = flow.steady_auto
        row = {"case_id": case.case_id, WINDOW: _window_seconds(flow, case.case_id),
               STEADY_SHARE: share, REPLICA_COST: replica, PRODUCTION_COST: production,
               AT_CAP: auto and steady.at_cap(fraction),
               LEAST_EXTENSION: (steady.least_extension(fraction, production_time) if auto
                                 else 0.0)}
        row.update({within_column(col): _series_value_noise(flow, case.case_id, col)
                    for col in columns})
        rows.append(row)
    return pd.DataFrame(rows).set_index("case_id") if rows else pd.DataFrame()


def capped_runs(noise: pd.DataFrame, ids) -> tuple[list[str], float]:
    """Of the runs ``ids`` that the noise table has, the ones whose steady window starts at
    its cap (:data:`AT_CAP`), and the production each of them needs at least: the most
    :data:`LEAST_EXTENSION` any of them needs (0 when none is capped). What the verdict's
    "too short" note says and what a round of a sequential study extends by."""
    capped = [i for i in ids if i in noise.index and bool(noise.at[i, AT_CAP])]
    return capped, max((float(noise.at[i, LEAST_EXTENSION]) for i in capped), default=0.0)
