"""Per-condition values with intervals, and the CG1 noise floor every CG error is held to.

Inputs: the case table (one row per usable case, :mod:`ligwf.report.tables`), the flow
profiles record (per-frame series of each case's steady window,
:mod:`ligwf.analysis.flow_run`) and the granule frame table (largest granule per frame).

Intervals (:mod:`ligwf.analysis.intervals`): frame metrics are block-bootstrapped over
frames and replicas, bounded to their range and never narrower than their within-run
error; run costs get a Student-t interval on the logarithm; one replica gets none.
The errors against CG1 (angle, velocity profile) are bootstrapped jointly with the CG1
reference, so the reference's own noise is in their intervals.

Noise floor: how far one CG1 run is from another CG1 run of the same scene (other seed).
With two or more CG1 replicas it is measured (each CG1 replica against the mean of the
others, the largest of these); with one it is estimated from that run's within-run noise
(the 95th percentile of the error between two independent block-bootstrap resamples of
the run). A CG error at or below the floor is marked ``within`` (indistinguishable from
seed noise), above it ``beyond``.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ligwf.analysis.flow import RIGID_FRAME_SHARE, relative_l2
from ligwf.analysis.intervals import (Interval, condition_draws, frame_metric_interval,
                                      interval_from_draws, nanmean, positive_replica_interval,
                                      run_draws)

UNIT = (0.0, 1.0)
POSITIVE = (0.0, math.inf)
ONE_GRANULE = 0.99   # a frame where one granule holds more than this of the bed


def _mean(a):
    return nanmean(a, axis=1)


def _std(a):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanstd(a, axis=1)


def _rel_fluct(a):
    with np.errstate(invalid="ignore", divide="ignore"):
        return _std(a) / _mean(a)


def _rigid_share(a):
    return np.mean(a > RIGID_FRAME_SHARE, axis=1)


def _one_granule(a):
    return np.mean(a > ONE_GRANULE, axis=1)


#: column -> (series name, statistic over frames, range)
FRAME_METRICS = {
    "angle_of_repose": ("angle", _mean, (-90.0, 90.0)),
    "angle_of_repose_std": ("angle", _std, POSITIVE),
    "rigid_frame_share": ("rigid", _rigid_share, UNIT),
    "rms_speed_rel_fluctuation": ("rms", _rel_fluct, POSITIVE),
    "largest_cluster_fraction": ("largest", _mean, UNIT),
    "one_granule_frame_share": ("largest", _one_granule, UNIT),
}
ERROR_METRICS = ("angle_error", "profile_error")


def _arr(values) -> np.ndarray:
    return np.array([np.nan if v is None else v for v in values], dtype=float)


def case_series(case_ids: list[str], profiles: dict, frames: pd.DataFrame) -> dict[str, dict]:
    """Per case: its steady-window frame series by name (angle, rigid, rms, largest,
    profile)."""
    out = {}
    for cid in case_ids:
        p = profiles.get(cid, {})
        s = {"angle": _arr(p.get("angle_series", [])), "rigid": _arr(p.get("rigid_series", [])),
             "rms": _arr(p.get("rms_series", []))}
        vf = p.get("v_frames")
        s["profile"] = (np.array([_arr(r) for r in vf]) if vf else np.empty((0, 0)))
        if not frames.empty and "largest_fraction" in frames:
            first = p.get("steady_from_step", -math.inf)
            ok = frames[(frames["case_id"] == cid) & (frames["step"] >= first)]
            if "status" in ok:
                ok = ok[ok["status"] == "ok"]
            s["largest"] = ok.sort_values("step")["largest_fraction"].to_numpy(float)
        else:
            s["largest"] = np.empty(0)
        out[cid] = s
    return out


@dataclass(frozen=True)
class Floor:
    """CG1-vs-CG1 noise floor of one error metric."""

    value: float
    source: str   # "measured over N CG1 replicas" | "estimated from 1 CG1 run" | "none"


class ConditionStats:
    """Intervals and noise floors of one sweep group's conditions."""

    def __init__(self, series: dict[str, dict], draws: int, seed: int):
        self.series, self.draws, self.seed = series, draws, seed

    def _runs(self, ids, name) -> list[np.ndarray]:
        return [self.series[c][name] for c in ids if c in self.series and len(self.series[c][name])]

    def frame_metric(self, ids, col) -> Interval:
        name, stat, bounds = FRAME_METRICS[col]
        return frame_metric_interval(self._runs(ids, name), bounds, self.draws, self.seed, stat)

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

    @staticmethod
    def _angle_err(ref, x):
        with np.errstate(invalid="ignore", divide="ignore"):
            return np.abs(x - ref) / np.abs(ref)

    def _spec(self, col):
        if col == "angle_error":
            return "angle", _mean, self._angle_err
        return "profile", _mean, relative_l2

    def error_metric(self, ids, ref_ids, col) -> Interval:
        name, stat, error = self._spec(col)
        value, comb, within, n = self._error_draws(ids, ref_ids, name, stat, error)
        return interval_from_draws(value, comb, within, n, POSITIVE)

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
                     "estimated from 1 CG1 run (within-run noise)")

    def scatter(self, ref_ids, col) -> tuple[float, str]:
        """CG1-vs-CG1 scatter of a frame metric: std over CG1 replicas, or with one CG1
        run its within-run standard error (the std a second run's value would have)."""
        ref = [c for c in ref_ids if c in self.series]
        name, stat, _ = FRAME_METRICS[col]
        runs = self._runs(ref, name)
        if len(runs) >= 2:
            vals = [float(stat(r[None])[0]) for r in runs]
            return float(np.std(vals, ddof=1)), f"std over {len(runs)} CG1 replicas"
        iv = self.frame_metric(ref, col)
        return iv.se_within, "within-run error of 1 CG1 run"


def cost_interval(values: pd.Series) -> Interval:
    """Run cost (positive, one value per replica)."""
    return positive_replica_interval(values.to_numpy(float))


def mark(error: float, floor: float) -> str:
    """``within`` / ``beyond`` the noise floor (``–`` when either is unknown)."""
    if not (math.isfinite(error) and math.isfinite(floor)):
        return "–"
    return "within" if error <= floor else "beyond"
