"""What would decide an undecided criterion, and what it costs: the variance components
of the run means and the half-width they predict after more sampling.

A run's steady-window mean varies from seed to seed for two reasons: the run's own
correlated frames (its **within-run** variance, ``s_frames^2 x 2 tau / n_frames``, which
falls as the window grows) and the seed's offset (the **between-run** variance, which no
run length removes). The sample variance of an arm's run means holds both; its within part
is the mean of the runs' own within-run variances (:func:`within_variance` of each run's
frame series), bounded by the sample variance; the rest is the between part
(:func:`components`).

Two ways to narrow Welch's interval of CG-n - CG1:

* **extend** the arm's existing runs by S seconds of production (continued from their
  restarts: no fill, no settle): the window of each run grows by ``steady_share x S`` and
  only the within part of its run mean shrinks (``v_within x W / (W + steady_share S)``);
  S is at least the arm's ``least_extension``, so that the steady window's truncation stays
  at most a quarter of production (half its cap: :mod:`ligwf.analysis.records.steady_window`);
* **add K replicas** to the arm: the variance of its mean shrinks as 1 / (R + K), the
  degrees of freedom grow.

:func:`cheapest` tries both on each arm, with the difference as measured, and returns the
cheapest option (in core-hours, from the costs the caller passes: the planner's rates) that
makes the (1 - 2 alpha) half-width smaller than the distance of the difference from the
budget, i.e. that would decide the two one-sided tests. The prediction assumes the
measured difference and variances stay; it is a plan, not a promise, and the report says
so. Pure: arrays in, numbers out.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import cached_property, lru_cache

import numpy as np

from ligwf.inference import behrens_fisher
from ligwf.inference.equivalence import (ALPHA, WELCH, WELCH_BF, degrees_of_freedom,
                                                finite_values, t_quantile)
from ligwf.analysis.records.intervals import autocorrelation_time

#: the kinds of option
EXTEND, REPLICAS = "extend", "replicas"
#: most replicas an arm is planned to get, and the longest extension (x the current window)
MOST_REPLICAS = 256
MOST_EXTENSION = 200.0


def within_variance(series) -> float:
    """Variance of one run's mean from its own frames: s^2 x 2 tau / n (nan with fewer
    than two finite frames; 0 for a constant series)."""
    x = np.asarray(series, float)
    x = x[np.isfinite(x)]
    if len(x) < 2:
        return math.nan
    return float(np.var(x, ddof=1) * 2.0 * autocorrelation_time(x) / len(x))


@dataclass(frozen=True)
class ArmRuns:
    """The runs of one arm of a comparison (:class:`ligwf.study.condition.Arm` names the
    side) as the planning sees them: per run its value (the
    steady-window mean), the within-run variance of that value, its window length (s), and
    the cost of a replica and of one second of production (core-seconds, per run), and the
    least extension its runs need to be steady (s of production per run,
    :func:`ligwf.analysis.records.steady_window.least_extension`: 0 when every window
    starts by a quarter of production)."""

    values: np.ndarray
    within: np.ndarray
    window: np.ndarray
    steady_share: float = 0.75          # share of added production that is steady window
    replica_core_seconds: float = math.nan
    production_core_seconds: float = math.nan   # per simulated second, per run
    least_extension: float = 0.0

    @property
    def n(self) -> int:
        return len(self.values)

    @cached_property
    def variance(self) -> float:
        """Sample variance of the run values."""
        return float(np.var(self.values, ddof=1)) if self.n > 1 else math.nan

    def scaled(self, factor: float) -> "ArmRuns":
        """The arm in another unit (values x factor, variances x factor^2)."""
        return ArmRuns(self.values * factor, self.within * factor**2, self.window,
                   self.steady_share, self.replica_core_seconds, self.production_core_seconds,
                   self.least_extension)


def arm(values, within=None, window=None, **kw) -> ArmRuns:
    """An :class:`ArmRuns` from lists (``within``/``window`` nan when unknown)."""
    v = np.asarray(values, float)
    keep = np.isfinite(v)
    w = np.full(len(v), math.nan) if within is None else np.asarray(within, float)
    t = np.full(len(v), math.nan) if window is None else np.asarray(window, float)
    return ArmRuns(v[keep], w[keep], t[keep], **kw)


def components(a: ArmRuns) -> tuple[float, float]:
    """(within, between) variance of one run value of ``a``: the mean of the runs' own
    within-run variances, at most the sample variance of the run values, and the rest of
    that variance (>= 0). Unknown within-run variances count as 0 (all of the scatter is
    then between runs: extension cannot help).

    Why the bound: the within part of a run value's variance cannot exceed the variance
    itself, and the frame-based estimate does on real drums: the angle of repose oscillates
    (a period of ~16 frames on the ladder's drum) and the self-consistent window stops
    after the first positive lobe of the autocorrelation, missing the negative lobes that
    average out in a run mean (docs/results/prediction_check/README.md). Unbounded, a plan
    shrank an over-stated within part and predicted an extension to widen the interval."""
    within = finite_values(a.within)
    w = float(within.mean()) if len(within) == a.n and a.n else 0.0
    total = a.variance
    if not math.isfinite(total):
        return w, math.nan
    w = min(w, total)
    return w, total - w


def run_variance(a: ArmRuns, extend_seconds: float = 0.0) -> float:
    """Predicted variance of one run value of ``a`` after ``extend_seconds`` more
    production on each run (the within part shrinks with the window); the sample
    variance when nothing is added."""
    if extend_seconds <= 0:
        return a.variance
    within, between = components(a)
    if within <= 0 or not np.isfinite(a.window).all():
        return a.variance
    grow = a.window / (a.window + a.steady_share * extend_seconds)
    # each run's within part shrinks with its own window; the bound scales them alike
    scale = within / float(np.mean(a.within))
    shrunk = float(np.nanmean(a.within * scale * grow))
    return between + shrunk


def half_width(x: ArmRuns, y: ArmRuns, alpha: float = ALPHA, add: tuple[int, int] = (0, 0),
               extend: tuple[float, float] = (0.0, 0.0), df_rule: str = WELCH) -> float:
    """Half-width of the (1 - 2 alpha) interval of mean(x) - mean(y) after ``add``
    replicas and ``extend`` seconds of production on every run (of x, of y), with the
    reference distribution the verdict's interval uses under ``df_rule``
    (:func:`~ligwf.inference.equivalence.difference_estimate`): Student's t at the rule's
    degrees of freedom, or the Behrens-Fisher distribution for unequal arms under
    ``WELCH_BF``."""
    if x.n < 2 or y.n < 2:
        return math.nan
    vx, vy = run_variance(x, extend[0]), run_variance(y, extend[1])
    nx, ny = x.n + add[0], y.n + add[1]
    se = math.sqrt(vx / nx + vy / ny)
    if se == 0:
        return 0.0
    # the variances are still estimated from the runs there are: their degrees of freedom
    # grow with added replicas, not with a longer window
    if df_rule == WELCH_BF and nx != ny:
        theta = math.atan2(math.sqrt(vy / ny), math.sqrt(vx / nx))
        return _bf_planned(round(theta, 3), float(nx - 1), float(ny - 1), alpha) * se
    df = degrees_of_freedom(vx, nx, vy, ny, df_rule)
    return _t_planned(float(f"{df:.3g}") if math.isfinite(df) else df, alpha) * se


@lru_cache(maxsize=4096)
def _bf_planned(theta: float, df_x: float, df_y: float, alpha: float) -> float:
    """The Behrens-Fisher 1 - alpha quantile at ``theta`` rounded to 3 decimals (a plan)."""
    return behrens_fisher.quantile(1.0 - alpha, theta, df_x, df_y)


@lru_cache(maxsize=4096)
def _t_planned(df: float, alpha: float) -> float:
    """t quantile at ``df`` rounded to 3 digits (a plan, searched over many counts)."""
    return t_quantile(df, alpha)


@dataclass(frozen=True)
class Option:
    """One way to decide: ``kind`` (extend | replicas) on ``arm`` (CG-n | CG1 | CG-n and
    CG1), the ``amount`` (seconds of production per run, or CG-n replicas; ``amount_cg1``
    the CG1 replicas), its ``core_hours``, and the half-width it predicts (in the
    criterion's unit)."""

    kind: str
    arm: str
    amount: float
    core_hours: float
    predicted_half_width: float
    runs: int = 0           # runs extended (extend)
    amount_cg1: float = 0.0

    def text(self, unit: str = "") -> str:
        cost = (f"~{self.core_hours:.2g} core-h" if math.isfinite(self.core_hours)
                else "cost unknown")
        u = f" {unit}" if unit else ""
        if self.kind == EXTEND:
            runs = f"each of the {self.runs} {self.arm} runs" if self.runs else f"each {self.arm} run"
            what = f"{self.amount:.3g} s more production on {runs}"
        else:
            parts = [f"{int(k)} more {name} replica{'s' if k != 1 else ''}"
                     for k, name in ((self.amount, "CG-n"), (self.amount_cg1, "CG1")) if k > 0]
            what = " and ".join(parts)
        return f"{what} ({cost}; predicted half-width {self.predicted_half_width:.3g}{u})"


def _replicas(x: ArmRuns, y: ArmRuns, gap: float, alpha: float, df_rule: str = WELCH
              ) -> Option | None:
    """The cheapest (kx, ky) replicas to add (unknown costs: the fewest in all): for each
    kx the fewest ky by bisection (the half-width falls with ky)."""
    cx = x.replica_core_seconds if math.isfinite(x.replica_core_seconds) else 1.0
    cy = y.replica_core_seconds if math.isfinite(y.replica_core_seconds) else 1.0
    best = None
    for kx in range(0, MOST_REPLICAS - x.n + 1):
        if best is not None and kx * cx >= best[0]:
            break                  # CG-n replicas alone already cost more than the best
        most = MOST_REPLICAS - y.n
        if not half_width(x, y, alpha, add=(kx, most), df_rule=df_rule) < gap:
            continue
        lo, hi = -1, most          # h(lo) >= gap (or lo = -1), h(hi) < gap
        while hi - lo > 1:
            mid = (lo + hi) // 2
            if mid >= 0 and half_width(x, y, alpha, add=(kx, mid), df_rule=df_rule) < gap:
                hi = mid
            else:
                lo = mid
        cost = kx * cx + hi * cy
        if kx + hi > 0 and (best is None or cost < best[0]):
            best = (cost, kx, hi)
        if hi == 0:                # more CG-n replicas only cost more from here on
            break
    if best is None:
        return None
    _, kx, ky = best
    known = math.isfinite(x.replica_core_seconds) or kx == 0
    known = known and (math.isfinite(y.replica_core_seconds) or ky == 0)
    arm = "CG-n and CG1" if kx and ky else ("CG-n" if kx else "CG1")
    hours = ((kx * x.replica_core_seconds if kx else 0.0)
             + (ky * y.replica_core_seconds if ky else 0.0)) / 3600.0
    return Option(REPLICAS, arm, kx, hours if known else math.nan,
                  half_width(x, y, alpha, add=(kx, ky), df_rule=df_rule), 0, ky)


def _extension(x: ArmRuns, y: ArmRuns, gap: float, alpha: float, which: tuple[bool, bool],
               df_rule: str = WELCH) -> Option | None:
    arms = [a for a, on in zip((x, y), which) if on]
    if any(not np.isfinite(a.window).all() or a.n < 2 for a in arms):
        return None
    longest = MOST_EXTENSION * max(float(np.max(a.window)) for a in arms) / min(
        a.steady_share for a in arms)

    def h(s: float) -> float:
        return half_width(x, y, alpha, extend=(s if which[0] else 0.0, s if which[1] else 0.0),
                          df_rule=df_rule)

    if not h(longest) < gap or h(0.0) < gap:
        return None                 # nothing decides it, or it is decided at this alpha
    # an extension keeps the steady window's truncation well below its cap: at least the
    # production its runs need for that (the steady module's rule), more if the gap asks
    least = max(a.least_extension for a in arms)
    lo, hi = 0.0, max(longest, least)
    for _ in range(60):
        mid = 0.5 * (lo + hi)
        lo, hi = (lo, mid) if h(mid) < gap else (mid, hi)
    s = float(f"{hi:.2g}")
    s = max(s if h(s) < gap else hi, least)
    cost = sum(a.n * a.production_core_seconds * s for a in arms) / 3600.0
    name = "CG-n and CG1" if all(which) else ("CG-n" if which[0] else "CG1")
    return Option(EXTEND, name, s, cost, h(s), sum(a.n for a in arms))


def options(x: ArmRuns, y: ArmRuns, difference: float, budget: float, alpha: float = ALPHA,
            df_rule: str = WELCH) -> list[Option]:
    """Every way that would decide the two one-sided tests of ``difference`` (CG-n - CG1,
    in the unit of the arms) against +-``budget``, with the variances as measured: more
    replicas of either arm, a longer production of either or both arms' runs. Sorted by
    core-hours (unknown costs last)."""
    gap = abs(abs(difference) - budget)
    if x.n < 2 or y.n < 2 or not gap > 0:
        return []
    found = [_replicas(x, y, gap, alpha, df_rule),
             _extension(x, y, gap, alpha, (True, False), df_rule),
             _extension(x, y, gap, alpha, (False, True), df_rule),
             _extension(x, y, gap, alpha, (True, True), df_rule)]
    return sorted((o for o in found if o is not None),
                  key=lambda o: (not math.isfinite(o.core_hours), o.core_hours, o.amount))


def cheapest(x: ArmRuns, y: ArmRuns, difference: float, budget: float,
             alpha: float = ALPHA, df_rule: str = WELCH) -> Option | None:
    """The cheapest of :func:`options` (None: nothing within the planned limits decides)."""
    found = options(x, y, difference, budget, alpha, df_rule)
    return found[0] if found else None


def dominant_arm(x: ArmRuns, y: ArmRuns) -> str:
    """The arm whose variance of the mean is the larger share of the difference's."""
    return "CG-n" if x.variance / x.n >= y.variance / y.n else "CG1"
