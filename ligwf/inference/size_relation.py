"""The size relation: how much steeper a Weber-scaled bed's angle of repose lies at CG-n,
as a function of x = (n - 1) d / D (d the CG1 bead diameter, D the drum's).

Why x: at a fixed drum the flowing layer keeps its thickness in mm, so a CG-n bed's layer
holds n times fewer grains across; the excess over CG1 grows with the grains lost, n - 1,
in units of the drum over the bead. Every committed study with CG1 and Weber levels is one
or more rows (excess of a level's mean over its CG1 mean, with its standard error); the
slope through the origin is fitted by weighted least squares with its scatter inflated by
the Birge ratio where the rows disagree beyond their errors
(``docs/results/extrapolation/size_relation.csv``, the figure beside it).

``ligwf check`` uses the fitted slope to say, before a core-hour is spent, how much steeper
each level is expected to be on the study's drum (:func:`expected_excess`), and says when
the drum lies outside the D / (n d) range the fit saw.
"""

from __future__ import annotations

import math
from collections.abc import Iterable
from dataclasses import dataclass

import numpy as np
import pandas as pd
from scipy import stats

#: the fit of docs/results/extrapolation/size_fit.csv (every committed Weber row, 5 rows
#: of 4 studies): excess angle (deg) = SLOPE x (n - 1) d / D, its 95 % interval, and the
#: D / (n d) the rows spanned (tests/inference/test_size_relation.py recomputes them)
SLOPE_DEG = 99.1
SLOPE_DEG_LO = 89.0
SLOPE_DEG_HI = 109.3
FITTED_D_OVER_ND = (12.5, 25.0)
#: the rows' columns
COLUMNS = ("study", "rule", "cg", "d_over_D", "x", "excess_deg", "excess_se", "replicas",
           "cg1_replicas")


@dataclass(frozen=True)
class SlopeFit:
    """excess = slope x, with its standard error, 95 % interval, the Birge ratio and the
    number of rows."""

    slope: float
    se: float
    lo: float
    hi: float
    birge: float
    rows: int


def excess_rows(cases: pd.DataFrame, study: str, d_over_D: float,
                column: str = "angle_of_repose") -> list[dict]:
    """One row per (rule, CG level > 1) of a case table with CG1 runs: the excess of the
    level's mean over the CG1 mean, with Welch's standard error."""
    ref = pd.to_numeric(cases.loc[cases["cg"] == 1.0, column], errors="coerce").dropna()
    if len(ref) < 2:
        return []
    out = []
    for (rule, cg), sub in cases[cases["cg"] > 1.0].groupby(["rule", "cg"]):
        v = pd.to_numeric(sub[column], errors="coerce").dropna()
        if len(v) < 2:
            continue
        se = math.sqrt(float(v.var(ddof=1)) / len(v) + float(ref.var(ddof=1)) / len(ref))
        out.append(dict(study=study, rule=str(rule), cg=float(cg), d_over_D=d_over_D,
                        x=(float(cg) - 1.0) * d_over_D,
                        excess_deg=float(v.mean() - ref.mean()), excess_se=se,
                        replicas=len(v), cg1_replicas=len(ref)))
    return out


def fit_slope(rows: Iterable[dict] | pd.DataFrame) -> SlopeFit:
    """Weighted least squares through the origin, excess = slope x (weights 1 / se^2);
    the standard error inflated by the Birge ratio sqrt(chi^2 / (rows - 1)) when above 1,
    the interval Student t at rows - 1 degrees of freedom."""
    t = pd.DataFrame(list(rows) if not isinstance(rows, pd.DataFrame) else rows)
    if len(t) < 2:
        return SlopeFit(math.nan, math.nan, math.nan, math.nan, math.nan, len(t))
    x, y, s = (t[c].to_numpy(float) for c in ("x", "excess_deg", "excess_se"))
    w = 1.0 / (s * s)
    slope = float(np.sum(w * x * y) / np.sum(w * x * x))
    se = float(1.0 / math.sqrt(np.sum(w * x * x)))
    chi2 = float(np.sum(w * (y - slope * x) ** 2))
    birge = math.sqrt(chi2 / (len(t) - 1))
    se *= max(1.0, birge)
    half = float(stats.t.ppf(0.975, len(t) - 1)) * se
    return SlopeFit(slope, se, slope - half, slope + half, birge, len(t))


@dataclass(frozen=True)
class ExpectedExcess:
    """The angle excess a Weber CG-n bed is expected to show on a drum, from the size
    relation, and whether the drum lies inside the range the relation was fitted on."""

    cg: float
    x: float
    value: float
    lo: float
    hi: float
    d_over_nd: float
    inside_fit: bool

    @property
    def text(self) -> str:
        where = ("inside" if self.inside_fit else "OUTSIDE")
        lo_r, hi_r = FITTED_D_OVER_ND
        return (f"CG{self.cg:g} is expected about {self.value:.2g} deg steeper than CG1 "
                f"[{self.lo:.2g}, {self.hi:.2g}] (x = (n - 1) d / D = {self.x:.3g}; "
                f"D / (n d) = {self.d_over_nd:.3g}, {where} the {lo_r:g}-{hi_r:g} the "
                f"relation was fitted on)")


def expected_excess(cg: float, d_over_D: float) -> ExpectedExcess:
    """The size relation's expected angle excess (deg) of Weber CG-``cg`` over CG1 on a
    drum with CG1 beads ``d_over_D`` of its diameter."""
    x = (cg - 1.0) * d_over_D
    d_over_nd = 1.0 / (cg * d_over_D)
    lo_r, hi_r = FITTED_D_OVER_ND
    return ExpectedExcess(cg, x, SLOPE_DEG * x, SLOPE_DEG_LO * x, SLOPE_DEG_HI * x, d_over_nd,
                          lo_r <= d_over_nd <= hi_r)
