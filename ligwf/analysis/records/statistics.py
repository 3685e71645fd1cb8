"""The statistics a recorded per-frame series is summarised with, by name.

A metric names its statistic (:class:`~ligwf.analysis.records.metrics.MetricSpec`); the
analysis stage uses :func:`value` for the per-case value of the flow table, the report
:func:`over_frames` on bootstrap draws (arrays ``(draws, frames, ...)``) and :func:`error`
for the errors against the CG1 reference. Adding a statistic means adding it here.
"""

from __future__ import annotations

import math
import warnings
from typing import Callable

import numpy as np

from ligwf.analysis.records.intervals import nanmean

#: frame statistics: a value of one run from its frames
MEAN = "mean"                             # mean of the finite frames
STD = "std"                               # standard deviation of the finite frames
RELATIVE_FLUCTUATION = "relative_fluctuation"   # std / mean
SHARE_ABOVE = "share_above"               # share of frames above the metric's threshold
FRAME_STATISTICS = (MEAN, STD, RELATIVE_FLUCTUATION, SHARE_ABOVE)
#: errors against the CG1 reference: of the mean over frames
RELATIVE_ERROR = "relative_error"         # |x - ref| / |ref| (a scalar series)
RELATIVE_L2 = "relative_l2"               # ||x - ref|| / ||ref|| over the bins (a profile)
ERROR_STATISTICS = (RELATIVE_ERROR, RELATIVE_L2)


def _nanstd(a, axis=None):
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)
        return np.nanstd(a, axis=axis)


def over_frames(statistic: str, threshold: float | None = None
                ) -> Callable[[np.ndarray], np.ndarray]:
    """The statistic over the frame axis (axis 1) of ``(draws, frames, ...)`` arrays;
    errors are taken of the mean over frames."""
    if statistic in (MEAN, *ERROR_STATISTICS):
        return lambda a: nanmean(a, axis=1)
    if statistic == STD:
        return lambda a: _nanstd(a, axis=1)
    if statistic == RELATIVE_FLUCTUATION:
        def fluctuation(a):
            with np.errstate(invalid="ignore", divide="ignore"):
                return _nanstd(a, axis=1) / nanmean(a, axis=1)
        return fluctuation
    if statistic == SHARE_ABOVE:
        return lambda a: np.mean(a > threshold, axis=1)
    raise ValueError(f"unknown statistic {statistic!r} (known: "
                     f"{', '.join(FRAME_STATISTICS + ERROR_STATISTICS)})")


def value(statistic: str, series, threshold: float | None = None) -> float:
    """The statistic of one run's series (nan when it has no finite frame)."""
    x = np.array([np.nan if v is None else v for v in series], dtype=float)
    finite = x[np.isfinite(x)]
    if statistic == SHARE_ABOVE:
        return float(np.mean(x > threshold)) if len(x) else math.nan
    if not len(finite):
        return math.nan
    if statistic == MEAN:
        return float(np.mean(finite))
    if statistic == STD:
        return float(np.std(finite))
    if statistic == RELATIVE_FLUCTUATION:
        mean = float(np.mean(finite))
        return float(np.std(finite) / mean) if mean > 0 else math.nan
    raise ValueError(f"{statistic!r} is not a frame statistic ({', '.join(FRAME_STATISTICS)})")


def relative_l2(v_ref: np.ndarray, v: np.ndarray) -> np.ndarray:
    """||v - v_ref|| / ||v_ref|| over the last axis (profile bins), on the bins both fill;
    broadcasts over leading axes (bootstrap draws). nan where no bin is common."""
    v_ref, v = np.asarray(v_ref, float), np.asarray(v, float)
    ok = np.isfinite(v_ref) & np.isfinite(v)
    diff = np.sqrt(np.sum(np.where(ok, (v - v_ref) ** 2, 0.0), axis=-1))
    norm = np.sqrt(np.sum(np.where(ok, v_ref**2, 0.0), axis=-1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(norm > 0, diff / np.where(norm > 0, norm, 1.0), np.nan)


def relative_error(ref, x):
    """|x - ref| / |ref|, elementwise."""
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.abs(x - ref) / np.abs(ref)


def error(statistic: str) -> Callable[[np.ndarray, np.ndarray], np.ndarray]:
    """``error(reference mean, mean)`` of an error statistic."""
    if statistic == RELATIVE_ERROR:
        return relative_error
    if statistic == RELATIVE_L2:
        return relative_l2
    raise ValueError(f"{statistic!r} is not an error statistic ({', '.join(ERROR_STATISTICS)})")
