"""Per-condition values with intervals, and the CG1 noise floor every CG error is held to.

Inputs: the case table (one row per usable case, :mod:`ligwf.inference.study_tables`), the flow
record (per-frame series of each case's steady window and the specification of every
metric: series, statistic, range, :class:`~ligwf.analysis.records.flow.FlowRecord`) and
the granule frame table (largest granule per frame).

Intervals (:mod:`ligwf.analysis.records.intervals`): frame metrics are block-bootstrapped over
frames and replicas, bounded to their range and never narrower than their within-run
error; run costs get a Student-t interval on the logarithm; one replica gets none.
The errors against CG1 (angle, velocity profile) are bootstrapped jointly with the CG1
reference, so the reference's own noise is in their intervals.

Noise floor: how far one CG1 run is from another CG1 run of the same scene (other seed).
With two or more CG1 replicas it is measured (each CG1 replica against the mean of the
others, the largest of these); with one it is estimated from that run's within-run noise
(the 95th percentile of the error between two independent block-bootstrap resamples of
the run), and that floor is labelled *indicative*. The floor decides only where the error's
interval does (:func:`mark`): ``beyond`` when the whole interval lies above the floor (a CG
effect), ``within`` when the whole interval lies at or below it (indistinguishable from
seed noise), otherwise ``undecided``, with the number of CG1 replicas that would decide
it. (Marking the point value against the floor called an error "beyond" whose interval
held 0, and a resumed run of the same study "within".)
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ligwf.analysis.records.flow import FlowRecord
from ligwf.analysis.records.intervals import (Interval, condition_draws, frame_metric_interval,
                                              interval_from_draws, nanmean,
                                              positive_replica_interval, run_draws)
from ligwf.analysis.records.metrics import GRANULE_METRICS, LARGEST_SERIES, MetricSpec
from ligwf.analysis.records.statistics import error as error_of


def report_metrics(flow: FlowRecord) -> dict[str, MetricSpec]:
    """Every metric of the report with a series: the flow record's (in its order), then
    the granule frame table's."""
    return {m.name: m for m in (*flow.metrics, *GRANULE_METRICS)}


def _arr(values) -> np.ndarray:
    return np.array([np.nan if v is None else v for v in values], dtype=float)


def case_series(case_ids: list[str], flow: FlowRecord, frames: pd.DataFrame
                ) -> dict[str, dict]:
    """Per case: its steady-window frame series by name (the flow record's, and the
    largest granule's share of the bed from the granule frame table)."""
    out = {}
    for cid in case_ids:
        c = flow.cases.get(cid)
        s = {}
        for name in {m.series for m in flow.metrics}:
            values = c.series.get(name, []) if c is not None else []
            if values and isinstance(values[0], list):     # a profile per frame
                s[name] = np.array([_arr(r) for r in values])
            else:
                s[name] = _arr(values)
        if not frames.empty and "largest_fraction" in frames and c is not None:
            ok = frames[(frames["case_id"] == cid) & (frames["step"] >= c.steady_from_step)]
            if "status" in ok:
                ok = ok[ok["status"] == "ok"]
            s[LARGEST_SERIES] = ok.sort_values("step")["largest_fraction"].to_numpy(float)
        else:
            s[LARGEST_SERIES] = np.empty(0)
        out[cid] = s
    return out


@dataclass(frozen=True)
class Floor:
    """CG1-vs-CG1 noise floor of one error metric."""

    value: float
    source: str   # "measured over N CG1 replicas" | "indicative: estimated from 1 CG1 run" | "none"


class ConditionStats:
    """Intervals and noise floors of one sweep group's conditions."""

    def __init__(self, series: dict[str, dict], draws: int, seed: int,
                 metrics: dict[str, MetricSpec]):
        self.series, self.draws, self.seed, self.metrics = series, draws, seed, metrics

    def _runs(self, ids, name) -> list[np.ndarray]:
        return [self.series[c][name] for c in ids if c in self.series and len(self.series[c][name])]

    def frame_metric(self, ids, col) -> Interval:
        m = self.metrics[col]
        return frame_metric_interval(self._runs(ids, m.series), m.bounds, self.draws,
                                     self.seed, m.over_frames())

    def _error_draws(self, ids, ref_ids, name, stat, error) -> tuple[float, np.ndarray, np.ndarray, int]:
        runs, ref = self._runs(ids, name), self._runs(ref_ids, name)
        if not runs or not ref:
            return math.nan, np.empty(0), np.empty(0), len(runs)
        rng = np.random.default_rng(self.seed)
        value = error(nanmean([stat(r[None])[0] for r in ref], axis=0),
                      nanmean([stat(r[None])[0] for r in runs], axis=0))
        c_comb, c_within = condition_draws(runs, self.draws, rng, stat)
        r_comb, r_within = condition_draws(ref, self.draws, rng, stat)
        if len(ref) < 2:
            r_comb = r_within
        return float(value), error(r_comb, c_comb), error(r_within, c_within), len(runs)

    def _spec(self, col):
        m = self.metrics[col]
        return m.series, m.over_frames(), error_of(m.statistic)

    def error_metric(self, ids, ref_ids, col) -> Interval:
        name, stat, error = self._spec(col)
        value, comb, within, n = self._error_draws(ids, ref_ids, name, stat, error)
        return interval_from_draws(value, comb, within, n, self.metrics[col].bounds)

    def floor(self, ref_ids, col) -> Floor:
        """Noise floor of an error metric from the CG1 runs ``ref_ids``."""
        name, stat, error = self._spec(col)
        ref = self._runs(ref_ids, name)
        if not ref:
            return Floor(math.nan, "none")
        values = [stat(r[None])[0] for r in ref]
        if len(ref) >= 2:
            errs = [error(nanmean(values[:k] + values[k + 1:], axis=0), values[k])
                    for k in range(len(ref))]
            return Floor(float(np.nanmax(errs)), f"measured over {len(ref)} CG1 replicas")
        rng = np.random.default_rng(self.seed + 1)
        a = run_draws(ref[0], self.draws, rng, stat)
        b = run_draws(ref[0], self.draws, rng, stat)
        e = np.asarray(error(a, b), float)
        e = e[np.isfinite(e)]
        return Floor(float(np.quantile(e, 0.95)) if len(e) else math.nan,
                     "indicative: estimated from 1 CG1 run (within-run noise)")

    def scatter(self, ref_ids, col) -> tuple[float, str]:
        """CG1-vs-CG1 scatter of a frame metric: std over CG1 replicas, or with one CG1
        run its within-run standard error (the std a second run's value would have)."""
        ref = [c for c in ref_ids if c in self.series]
        m = self.metrics[col]
        stat, runs = m.over_frames(), self._runs(ref, m.series)
        if len(runs) >= 2:
            vals = [float(stat(r[None])[0]) for r in runs]
            return float(np.std(vals, ddof=1)), f"std over {len(runs)} CG1 replicas"
        iv = self.frame_metric(ref, col)
        return iv.se_within, "within-run error of 1 CG1 run"


def cost_interval(values: pd.Series) -> Interval:
    """Run cost (positive, one value per replica)."""
    return positive_replica_interval(values.to_numpy(float))


#: The most CG1 replicas :func:`mark` suggests; more means the error sits on the floor.
MAX_SUGGESTED_REPLICAS = 64


def replicas_to_decide(error: float, lo: float, hi: float, floor: float,
                       cg1_replicas: int) -> int | None:
    """CG1 replicas that would make the interval [lo, hi] of ``error`` clear the floor,
    assuming its half-width is the CG1 reference's noise and shrinks as 1 / sqrt(replicas):
    ``ceil(R0 (w / |error - floor|)^2)``, at least one more than now; None when the error
    sits on the floor (no number of replicas decides)."""
    gap, half = abs(error - floor), 0.5 * (hi - lo)
    if gap <= 0.0 or not math.isfinite(half):
        return None
    need = math.ceil(max(cg1_replicas, 1) * (half / gap) ** 2 - 1e-9)   # rounding of lo, hi
    return max(need, cg1_replicas + 1)


def mark(error: float, floor: float, lo: float = math.nan, hi: float = math.nan,
         cg1_replicas: int = 1) -> str:
    """A CG error against the CG1 noise floor, decided by its 95 % interval [lo, hi]:
    ``beyond`` (lo > floor), ``within`` (hi <= floor), else ``undecided: ...`` saying what
    would decide it (``–`` when the error or the floor is unknown). Without an interval
    (one CG-n replica) nothing is decided."""
    if not (math.isfinite(error) and math.isfinite(floor)):
        return "–"
    if not (math.isfinite(lo) and math.isfinite(hi)):
        return "undecided: 1 replica, no interval (add CG-n replicas)"
    if lo > floor:
        return "beyond"
    if hi <= floor:
        return "within"
    need = replicas_to_decide(error, lo, hi, floor, cg1_replicas)
    if need is None:
        return "undecided: the error sits on the floor"
    if need > MAX_SUGGESTED_REPLICAS:
        return (f"undecided: the error is close to the floor (over {MAX_SUGGESTED_REPLICAS} "
                "CG1 replicas would be needed)")
    return f"undecided: about {need} CG1 replicas would decide"
