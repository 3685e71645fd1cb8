"""The extrapolated CG1 reference applied to a study's tables: the size ratio d / D of its
drum, the CG1 cost the planner predicts (the speedup of a sweep without CG1), and the
table of every extrapolated CG1 value beside the measured one where CG1 ran
(``report/extrapolation.csv``, :data:`EXTRAPOLATION_COLUMNS`).

The statistics are :mod:`ligwf.inference.extrapolation`; the verdict's criteria judged
against the reference are :mod:`ligwf.inference.extrapolated`.
"""

from __future__ import annotations

import math
from collections.abc import Iterable, Mapping

import numpy as np
import pandas as pd

from ligwf.engine.plan import case_load, estimated_seconds
from ligwf.errors import ConfigError
from ligwf.inference import extrapolation as ex
from ligwf.inference.size_relation import SLOPE_DEG
from ligwf.scene.model import Scene
from ligwf.scene.scaling import scale

#: the case-table column whose slope scale is the size relation's (the angle of repose)
ANGLE_COLUMN = "angle_of_repose"
#: the 95 % interval the table prints (the verdict's tests use their own alpha)
TABLE_ALPHA = 0.025

EXTRAPOLATION_COLUMNS = (
    "group", "rule", "column", "levels", "replicas", "extrapolated", "lo", "hi",
    "half_width", "noise_se", "model_term", "df", "form", "lack_of_fit_p", "observed_order",
    "slope_per_level", "cg1_measured", "cg1_se", "cg1_replicas", "cg1_inside")


def size_ratio(scene: Mapping) -> float:
    """d / D of a CG1 scene record (a case's scene record, its ``scene``): the number-weighted mean
    bead diameter over the drum's diameter (nan when the record lacks either)."""
    try:
        sizes = scene["particles"]["size_distribution"]
        d = sum(float(s["diameter"]) * float(s["fraction"]) for s in sizes) / sum(
            float(s["fraction"]) for s in sizes)
        return d / float(scene["drum"]["diameter"])
    except (KeyError, TypeError, ValueError, ZeroDivisionError):
        return math.nan


def slope_scale(column: str, ratio: float) -> float:
    """The typical change per CG level the model term's prior scales with: the size
    relation's for the angle of repose (deg), none (the fit's own slope) for the rest."""
    return SLOPE_DEG * ratio if column == ANGLE_COLUMN and math.isfinite(ratio) else 0.0


def planned_cg1_speedup(scene: Mapping, cg: float, rule: str) -> float:
    """The planner's CG1 core-seconds per simulated second over its CG-``cg`` ones, both
    on one rank (:func:`ligwf.engine.plan.estimated_seconds`: the measured per-particle-step
    rates, not a timing of this study): the speedup a sweep without CG1 reports."""
    try:
        model = Scene.model_validate(dict(scene))
        per_second = []
        for n, r in ((1.0, "none"), (float(cg), rule)):
            s = scale(model, n, r)
            seconds = estimated_seconds(case_load(f"cg{n:g}", s), 1)
            per_second.append(seconds / (s.total_steps * s.numerics.dt))
        return per_second[0] / per_second[1]
    except (ConfigError, ValueError, TypeError, KeyError, ZeroDivisionError):
        return math.nan


def _values(runs: pd.DataFrame, column: str) -> np.ndarray:
    return pd.to_numeric(runs[column], errors="coerce").to_numpy(float) if (
        column in runs) else np.array([])


def level_values(runs: pd.DataFrame, column: str) -> dict[float, np.ndarray]:
    """``{n: run values}`` of the CG-n levels (n > 1) of one rule's runs."""
    return {float(n): _values(g, column) for n, g in runs.groupby("cg") if float(n) > 1.0}


def extrapolation_rows(cases: pd.DataFrame, columns: Iterable[str], ratio: float,
                       groups: Iterable[str] | None = None) -> pd.DataFrame:
    """Every (group, rule, column) with two or more CG-n levels: the extrapolated CG1 value
    with its 95 % interval and checks, and the measured CG1 mean where CG1 ran. A group
    whose two rules both pass the checks gets a ``weber - bond`` row: their disagreement
    (both target the same CG1)."""
    rows = []
    if cases.empty or "cg" not in cases:
        return pd.DataFrame(columns=EXTRAPOLATION_COLUMNS)
    for group, in_group in cases.groupby(cases["group"].astype(str), sort=True):
        if groups is not None and group not in set(groups):
            continue
        cg1 = in_group[in_group["cg"] == 1.0]
        for column in columns:
            fits = {}
            for rule, runs in in_group[in_group["cg"] > 1.0].groupby(
                    in_group["rule"].astype(str)):
                e = ex.extrapolate(level_values(runs, column), ratio, TABLE_ALPHA,
                                   slope_scale=slope_scale(column, ratio))
                if not math.isfinite(e.value):
                    continue
                fits[rule] = e
                ref = _values(cg1, column)
                ref = ref[np.isfinite(ref)]
                m = float(ref.mean()) if len(ref) else math.nan
                rows.append(dict(
                    group=group, rule=rule, column=column,
                    levels=" ".join(f"{n:g}" for n in e.levels),
                    replicas=" ".join(str(r) for r in e.replicas), extrapolated=e.value,
                    lo=e.lo, hi=e.hi, half_width=e.half_width, noise_se=e.se,
                    model_term=e.model_term, df=e.df, form=e.form,
                    lack_of_fit_p=e.lack_of_fit_p, observed_order=e.observed_order,
                    slope_per_level=e.slope, cg1_measured=m,
                    cg1_se=float(ref.std(ddof=1) / math.sqrt(len(ref))) if len(ref) > 1
                    else math.nan, cg1_replicas=len(ref),
                    cg1_inside=(bool(e.lo <= m <= e.hi) if math.isfinite(m)
                                and e.has_interval else None)))
            if {"weber", "bond"} <= set(fits) and all(
                    fits[r].form == ex.CHECKED for r in ("weber", "bond")):
                d = ex.disagreement(fits["weber"], fits["bond"], TABLE_ALPHA)
                rows.append(dict(group=group, rule="weber - bond", column=column,
                                 extrapolated=d.value, lo=d.lo, hi=d.hi,
                                 half_width=(d.hi - d.lo) / 2, df=d.df, form=ex.CHECKED))
    return pd.DataFrame(rows, columns=EXTRAPOLATION_COLUMNS)
