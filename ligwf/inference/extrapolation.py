"""The CG1 value of a flow criterion extrapolated from CG-n levels of one scaling rule,
as CFD extrapolates a grid-converged value from three grids (Richardson; Roache's grid
convergence index; ASME V&V 20).

Why: at a fixed drum the flowing layer keeps its thickness in mm, so it holds fewer grains
at CG-n and a Weber-scaled bed's angle steepens about linearly in the number of grains it
lost: on every committed study the excess over CG1 collapses on (n - 1) d / D. Where CG1
cannot run (the source study's drum: 360,000 beads), the levels that can run say where
CG1 lies.

**The form.** ``theta(n) = theta_1 + b (n - 1)``: first order in the size ratio, fitted by
ordinary least squares on the level means (every run a replicate of its level). The
extrapolated value is then a fixed linear combination ``sum_k c_k m_k`` of the level means,
and so is the difference CG-n - extrapolated CG1 that the verdict judges (its weights
``e_n - c``: the level judged is part of its own reference, and the contrast carries that
covariance exactly). Its variance is ``sum_k w_k^2 s_k^2 / R_k`` (the run-to-run variance
of each level: frames' correlation and seed offsets included, as for every interval of the
verdict), with Satterthwaite's degrees of freedom.

**The model term.** A straight line through levels that curve leaves a bias ``c B`` with
``c`` the curvature and ``B = sum_k c_k (n_k - 1)^2`` a property of the design. The
curvature is an unknown of the drum: it is given a prior, normal with standard deviation
``CURVATURE_PRIOR x (d / D) x |b|`` (a relative curvature of the size relation of
CURVATURE_PRIOR per unit of x = (n - 1) d / D: the committed ladders' three estimates,
1.2-7.2 with standard errors of 4-5 each, are consistent with no curvature and with about
this spread; ``docs/results/extrapolation/size_relation.csv``). The model term
``u = |B| CURVATURE_PRIOR (d / D) |b|`` is then a standard uncertainty added to the noise in
quadrature, as the GUM adds a type B term: half-width ``t(df) sqrt(se^2 + u^2)`` with the
noise's Satterthwaite df (the prior's part taken as known). Its coverage on synthetic
ladders whose curvature is drawn from that prior, and at fixed curvatures beside, is
measured by ``benchmarks/bench_extrapolation.py``.

**The checks of the form.** With three or more levels: lack of fit, the Wald test of the
second-difference contrasts (the part of the level means no line explains) against their
run-to-run noise, at ``alpha_form``; and the observed order p of
``theta_1 + b (n - 1)^p`` through three levels (printed, as CFD prints it; a noisy number at
few replicas, so not a gate). Two levels cannot check the form: the value is printed
"unchecked".
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from dataclasses import dataclass

import numpy as np
from scipy import optimize, stats

from ligwf.inference.equivalence import ALPHA, Estimate, finite_values, t_quantile

#: the standard deviation of the prior on the size relation's relative curvature c / b, per
#: unit of (n - 1) d / D. The three committed ladders with CG1, CG2 and CG3 estimate it as
#: -8.9 +- 4.2, -1.3 +- 5.7 and +5.5 +- 7.3 (the first two share their CG-n runs); the
#: method of moments gives a spread of about 1.7 beyond their noise, the first one alone a
#: concave curve of about 4 after one standard error: 4 is taken
#: (docs/results/extrapolation/size_relation.csv holds the rows)
CURVATURE_PRIOR = 4.0
#: the level of the lack-of-fit check (a rejection says the form does not hold)
ALPHA_FORM = 0.05

#: form states
CHECKED, UNCHECKED, REJECTED = "checked", "unchecked", "rejected"


@dataclass(frozen=True)
class Level:
    """The run values (one per run: its steady-window mean) of one CG level n."""

    n: float
    values: np.ndarray

    @property
    def replicas(self) -> int:
        return int(len(self.values))

    @property
    def mean(self) -> float:
        return float(np.mean(self.values)) if len(self.values) else math.nan

    @property
    def variance_of_mean(self) -> float:
        return (float(np.var(self.values, ddof=1)) / len(self.values)
                if len(self.values) > 1 else math.nan)


@dataclass(frozen=True)
class Extrapolation:
    """The CG1 value extrapolated from the levels of one rule, with its (1 - 2 alpha)
    interval (noise and model term), the fitted slope per level and the form's checks."""

    value: float
    lo: float
    hi: float
    se: float                 # the noise part alone
    df: float                 # effective df of noise and model term together
    noise_df: float           # Satterthwaite df of the noise alone
    model_term: float         # u: the curvature's standard uncertainty, added in quadrature
    slope: float              # b: change per CG level (n -> n + 1)
    slope_se: float
    levels: tuple[float, ...]
    replicas: tuple[int, ...]
    weights: tuple[float, ...]   # c_k: value = sum c_k m_k
    form: str                 # CHECKED | UNCHECKED | REJECTED
    lack_of_fit_p: float      # nan with two levels
    observed_order: float     # nan unless three levels give one
    alpha: float = ALPHA

    @property
    def half_width(self) -> float:
        return (self.hi - self.lo) / 2.0

    @property
    def has_interval(self) -> bool:
        return math.isfinite(self.lo) and math.isfinite(self.hi)

    @property
    def form_text(self) -> str:
        """One phrase on the form's checks, with the numbers."""
        order = (f", observed order {self.observed_order:.2g}"
                 if math.isfinite(self.observed_order) else "")
        if self.form == UNCHECKED:
            return "form unchecked (two levels: a third level would test the line)"
        word = "holds" if self.form == CHECKED else "rejected"
        return (f"linear form {word} (lack of fit p = {self.lack_of_fit_p:.2g} over "
                f"{len(self.levels)} levels{order})")


NO_EXTRAPOLATION = Extrapolation(math.nan, math.nan, math.nan, math.nan, math.nan, math.nan,
                                 math.nan, math.nan, math.nan, (), (), (), UNCHECKED, math.nan,
                                 math.nan)


def levels_from(values: Mapping[float, object]) -> tuple[Level, ...]:
    """The levels of ``{n: run values}`` with a finite value, sorted by n (CG1 left out:
    it is what is extrapolated to)."""
    out = []
    for n, v in sorted(values.items()):
        x = finite_values(v)
        if float(n) > 1.0 and len(x):
            out.append(Level(float(n), x))
    return tuple(out)


def weights(ns: np.ndarray, at: float = 1.0) -> np.ndarray:
    """c_k: the ordinary least-squares line through (n_k, m_k) evaluated at ``at``, as a
    combination sum c_k m_k of the level means."""
    x = ns - 1.0
    xbar = float(np.mean(x))
    sxx = float(np.sum((x - xbar) ** 2))
    return 1.0 / len(x) + (at - 1.0 - xbar) * (x - xbar) / sxx


def contrast(levels: tuple[Level, ...], w: np.ndarray) -> tuple[float, float, float]:
    """(value, se, Satterthwaite df) of ``sum w_k m_k`` over independent levels."""
    value = float(np.dot(w, [lv.mean for lv in levels]))
    parts = np.array([wk * wk * lv.variance_of_mean for wk, lv in zip(w, levels)])
    if not np.all(np.isfinite(parts)):
        return value, math.nan, math.nan
    var = float(np.sum(parts))
    den = float(sum(p * p / (lv.replicas - 1) for p, lv in zip(parts, levels) if p > 0))
    df = var * var / den if den > 0 else math.inf
    return value, math.sqrt(var), df


def bias_factor(ns: np.ndarray, w: np.ndarray) -> float:
    """B = sum w_k (n_k - 1)^2: the bias of ``sum w_k m_k`` per unit of curvature c."""
    return float(np.dot(w, (ns - 1.0) ** 2))


def lack_of_fit(levels: tuple[Level, ...]) -> float:
    """p-value of the Wald test that the level means lie on a line (nan below three
    levels or without every level's variance): the L - 2 contrasts orthogonal to the
    line, against their run-to-run covariance, referred to F(L - 2, df) with the smallest
    Satterthwaite df of the contrasts."""
    L = len(levels)
    if L < 3:
        return math.nan
    ns = np.array([lv.n for lv in levels])
    design = np.column_stack([np.ones(L), ns - 1.0])
    q, _ = np.linalg.qr(np.column_stack([design, np.eye(L)]))
    basis = q[:, 2:L]                         # orthonormal, orthogonal to 1 and n
    means = np.array([lv.mean for lv in levels])
    var = np.array([lv.variance_of_mean for lv in levels])
    if not np.all(np.isfinite(var)):
        return math.nan
    y = basis.T @ means
    cov = basis.T @ np.diag(var) @ basis
    if not np.all(np.linalg.eigvalsh(cov) > 0):
        return 0.0 if np.any(np.abs(y) > 0) else 1.0
    wald = float(y @ np.linalg.solve(cov, y))
    df = min(contrast(levels, basis[:, j])[2] for j in range(L - 2))
    k = L - 2
    if not math.isfinite(df):
        return float(stats.chi2.sf(wald, k))
    return float(stats.f.sf(wald / k, k, df))


def observed_order(levels: tuple[Level, ...]) -> float:
    """p of ``theta_1 + b (n - 1)^p`` through the three finest levels' means (nan when the
    differences change sign or no p in [0.05, 10] fits)."""
    if len(levels) < 3:
        return math.nan
    lv = levels[:3]
    x = np.array([v.n - 1.0 for v in lv])
    m = np.array([v.mean for v in lv])
    d1, d2 = m[1] - m[0], m[2] - m[1]
    if d1 == 0 or d2 == 0 or (d1 > 0) != (d2 > 0):
        return math.nan
    ratio = d1 / d2

    def g(p: float) -> float:
        return (x[1] ** p - x[0] ** p) / (x[2] ** p - x[1] ** p) - ratio

    lo, hi = 0.05, 10.0
    if g(lo) * g(hi) > 0:
        return math.nan
    return float(optimize.brentq(g, lo, hi, xtol=1e-6))


def model_term(ns: np.ndarray, c: np.ndarray, slope: float, size_ratio: float,
               curvature_prior: float, slope_scale: float = 0.0) -> float:
    """u = |B| x curvature_prior x (d / D) x b: the standard uncertainty of the line's
    bias at the curvature's prior sd. The fitted slope b itself moves with the curvature (a
    concave relation flattens the line through coarse levels towards 0, and the prior with
    it), so a criterion with a known typical slope per level (the angle: the size
    relation's, SLOPE_DEG x d / D) passes it as ``slope_scale``, used instead of the fit's."""
    scale = abs(slope_scale) if slope_scale else abs(slope)
    return abs(bias_factor(ns, c)) * curvature_prior * size_ratio * scale


def effective_df(se: float, df: float, model: float) -> float:
    """The Welch-Satterthwaite degrees of freedom of se^2 + u^2 with the model term known
    (infinite df), as the GUM combines a type A and a type B term: the t quantile then
    inflates the noise, not the prior."""
    if not (math.isfinite(df) and se > 0):
        return math.inf if math.isfinite(se) else math.nan
    return (se * se + model * model) ** 2 / (se ** 4 / df)


def extrapolate(values: Mapping[float, object], size_ratio: float, alpha: float = ALPHA,
                curvature_prior: float = CURVATURE_PRIOR, at: float = 1.0,
                slope_scale: float = 0.0) -> Extrapolation:
    """The value at CG level ``at`` (CG1) from the CG-n levels of ``{n: run values}``
    (``size_ratio`` = d / D, the CG1 diameter over the drum's: the model term's scale;
    ``slope_scale``: see :func:`model_term`). Needs two levels with a value; an interval
    needs two runs at every level."""
    levels = levels_from(values)
    if len(levels) < 2:
        return NO_EXTRAPOLATION
    ns = np.array([lv.n for lv in levels])
    w = weights(ns, at)
    value, se, df = contrast(levels, w)
    slope_w = weights(ns, at + 1.0) - w
    slope, slope_se, _ = contrast(levels, slope_w)
    model = model_term(ns, w, slope, size_ratio, curvature_prior, slope_scale)
    lof = lack_of_fit(levels)
    form = UNCHECKED if len(levels) < 3 else (
        REJECTED if math.isfinite(lof) and lof < ALPHA_FORM else CHECKED)
    if math.isfinite(se):
        df_total = effective_df(se, df, model)
        half = t_quantile(df_total, alpha) * math.hypot(se, model)
        lo, hi = value - half, value + half
    else:
        lo = hi = math.nan
        df_total = math.nan
    return Extrapolation(value, lo, hi, se, df_total, df, model, slope, slope_se,
                         tuple(float(n) for n in ns), tuple(lv.replicas for lv in levels),
                         tuple(float(c) for c in w), form, lof, observed_order(levels), alpha)


def level_difference(values: Mapping[float, object], n: float, size_ratio: float,
                     alpha: float = ALPHA, curvature_prior: float = CURVATURE_PRIOR,
                     slope_scale: float = 0.0) -> Estimate:
    """CG-n - extrapolated CG1 as one contrast of the level means (the level judged is
    part of its reference); ``se`` is the noise and the model term in quadrature, so the
    two one-sided tests' p-values (:func:`ligwf.inference.equivalence.equivalence`)
    match the interval."""
    levels = levels_from(values)
    ns = np.array([lv.n for lv in levels])
    if len(levels) < 2 or float(n) not in set(ns.tolist()):
        return Estimate(math.nan, math.nan, math.nan, math.nan, math.nan)
    c = weights(ns, 1.0)
    w = (ns == float(n)).astype(float) - c
    value, se, df = contrast(levels, w)
    slope, _, _ = contrast(levels, weights(ns, 2.0) - c)
    model = model_term(ns, c, slope, size_ratio, curvature_prior, slope_scale)
    if not math.isfinite(se):
        return Estimate(value, math.nan, math.nan, math.nan, math.nan)
    total, df_total = math.hypot(se, model), effective_df(se, df, model)
    half = t_quantile(df_total, alpha) * total
    return Estimate(value, value - half, value + half, total, df_total)


def disagreement(a: Extrapolation, b: Extrapolation, alpha: float = ALPHA) -> Estimate:
    """a - b of two rules' extrapolated CG1 values (independent runs): both target the same
    CG1, so an interval that excludes 0 says at least one of them does not extrapolate."""
    if not (a.has_interval and b.has_interval):
        return Estimate(a.value - b.value, math.nan, math.nan, math.nan, math.nan)
    noise = a.se ** 2 + b.se ** 2
    den = ((a.se ** 4 / a.noise_df if math.isfinite(a.noise_df) else 0.0)
           + (b.se ** 4 / b.noise_df if math.isfinite(b.noise_df) else 0.0))
    total = math.sqrt(noise + a.model_term ** 2 + b.model_term ** 2)
    df = total ** 4 / den if den > 0 else math.inf
    d, half = a.value - b.value, t_quantile(df, alpha) * total
    return Estimate(d, d - half, d + half, total, df)
