"""The velocity profile's fail test simulated: the null distribution of the bins' F ratio
(sum of squared bin differences over the sum of their estimated variances) drawn under the
runs' own covariance of depth bins, a parametric bootstrap with a fixed seed.

Why: the noncentral F matches two moments of a weighted sum of correlated squared bin
differences with an effective number of bins k_e estimated from few runs; its upper tail
was too thin, so the fail test erred up to 0.065 on bins correlated like real profiles
(docs/results/verdict_rates/profiles.txt). Simulated under the runs' sample covariance, whose
eigenvalues spread more than the truth's, the fail side errs at most 0.044 there and is
conservative on independent bins (profiles_2.txt). :func:`ligwf.inference.equivalence.norm_estimate`
takes the lower bound from here under the simulated rules (``equivalence.SIMULATED_RULES``).

The same draws also give a candidate upper bound (the sixth verdict_rates run, profiles_3.txt):
the distance along the noise's largest direction (:meth:`SimulatedNull.largest`), where
the cross term 2 s a is widest. Along the observed direction the simulated upper bound
covered 0.86-0.92 on correlated bins at offset 0 (profiles_2's registration), so that
direction is not used for it. Measured, the smaller of it and the correlated rule's covered
0.950-0.992, still above 0.99 at offset 0 (profiles_3.txt check 1 failed): not the verdict's.

A third (the seventh run, profiles_4.txt): in each draw the distance along its own
direction drawn from the difference's fiducial distribution, the observed difference of the
mean profiles less an independent draw of the noise (:meth:`SimulatedNull.fiducial`). The
true difference's direction is the null's nuisance; the observed direction leans towards
quiet bins exactly when the distance looks small (the studies an upper bound must not
miss), the largest direction is the least favourable one; the fiducial draw averages over
the directions the runs leave possible. Measured, all four registered checks held
(0.955-0.972 on correlated bins, 0.950-0.981 on independent ones): the verdict's upper bound
since, the smaller of it and the correlated rule's.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np


#: draws of the simulated null and their seed (fixed: the same runs give the same bounds)
SIMULATED_DRAWS, SIMULATED_SEED = 2000, 20261207


def sample_correlation(x: np.ndarray, y: np.ndarray) -> np.ndarray:
    """The depth bins' sample correlation matrix from the runs' residuals pooled over both
    arms (each scaled per arm and bin to unit variance; the noise-corrected squares of
    :func:`ligwf.inference.equivalence.bin_correlation2` start from it); of
    rank at most R1 + R2 - 2, so its eigenvalues spread more than the truth's (fewer
    effective bins: a heavier upper tail, the conservative side of a fail test)."""
    parts = []
    for a in (x, y):
        res = a - a.mean(axis=0)
        sd = res.std(axis=0, ddof=1)
        parts.append(np.divide(res, sd, out=np.zeros_like(res), where=sd > 0))
    res = np.vstack(parts)
    norms = np.sqrt(np.sum(res * res, axis=0))
    outer = np.outer(norms, norms)
    r = np.divide(res.T @ res, outer, out=np.zeros((res.shape[1],) * 2), where=outer > 0)
    np.fill_diagonal(r, 1.0)
    return r


def _eig(cov: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    w, u = np.linalg.eigh(0.5 * (cov + cov.T))
    return np.clip(w, 0.0, None), u


@dataclass(frozen=True)
class SimulatedNull:
    """Draws of the bins' F ratio around a distance s along the unit direction u:
    T*(s) = (s^2 + 2 s a + b) / v, with a = u . e, b = |e|^2 (e: the simulated noise of the
    bin differences) and v the simulated sum of the bins' estimated variances;
    ``observed`` is the study's sum_k d_k^2 / sum_k v_k."""

    a: np.ndarray
    b: np.ndarray
    v: np.ndarray
    observed: float
    #: a along the eigenvector of the largest eigenvalue of the bin differences' simulated
    #: covariance (the direction whose cross term spreads T* most); None: not drawn
    a_largest: np.ndarray | None = None
    #: a along each draw's own direction from the difference's fiducial distribution (the
    #: observed difference less an independent draw of the noise); None: not drawn
    a_fiducial: np.ndarray | None = None

    def largest(self) -> "SimulatedNull":
        """The same draws with the distance along the noise's largest direction."""
        if self.a_largest is None:
            raise ValueError("a_largest: not drawn (simulated_null draws it)")
        return SimulatedNull(self.a_largest, self.b, self.v, self.observed)

    def fiducial(self) -> "SimulatedNull":
        """The same draws with the distance of each along its own direction drawn from the
        difference's fiducial distribution: the direction, the null's nuisance, averaged
        over what the runs say about it rather than fixed."""
        if self.a_fiducial is None:
            raise ValueError("a_fiducial: not drawn (simulated_null draws it)")
        return SimulatedNull(self.a_fiducial, self.b, self.v, self.observed)

    def _count(self) -> tuple[np.ndarray, np.ndarray, float]:
        """The distances s >= 0 where a draw's T*(s) enters or leaves [0, observed] (T* is
        quadratic in s: each draw is at or below the observed ratio on one interval), the
        number of draws at or below it on the segment after each, and the number at s = 0."""
        disc = self.a * self.a - self.b + self.observed * self.v
        root = np.sqrt(np.clip(disc, 0.0, None))
        start, end = np.maximum(-self.a - root, 0.0), -self.a + root
        ok = (disc >= 0) & (end >= 0)
        start, end = start[ok], end[ok]
        at0 = float(np.sum(start <= 0.0))
        later = start[start > 0]
        points = np.concatenate([later, end])
        steps = np.concatenate([np.ones(len(later)), -np.ones(len(end))])
        order = np.lexsort((-steps, points))      # at a tie, a draw enters before one leaves
        return points[order], at0 + np.cumsum(steps[order]), at0

    def bounds(self, alpha: float) -> tuple[float, float]:
        """(lower, upper) bounds of the distance s: the lower the smallest s at which fewer
        than 1 - alpha of the draws lie at or below the observed ratio (a distance below it
        puts the observed ratio in the upper alpha tail), the upper the largest s at which
        more than alpha do."""
        n = len(self.v)
        points, count, at0 = self._count()
        above = np.nonzero(count > alpha * n)[0]
        hi = (float(points[above[-1] + 1]) if len(above) and above[-1] + 1 < len(points)
              else (math.inf if len(above) else 0.0))
        below = np.nonzero(count < (1.0 - alpha) * n)[0]
        lo = 0.0 if at0 < (1.0 - alpha) * n else (float(points[below[0]]) if len(below)
                                                   else math.inf)
        return lo, hi

    def fail_p(self, budget: float) -> float:
        """The largest share, over distances s in [0, budget], of draws whose ratio is at
        least the observed one: the fail test's p-value, at most alpha exactly when the
        lower bound is at least the budget."""
        n = len(self.v)
        points, count, at0 = self._count()
        inside = count[points <= budget]
        least = min(at0, float(inside.min())) if len(inside) else at0
        return float(min(1.0, max(0.0, (n - least) / n)))   # (exactly alpha at the bound)


def simulated_null(x: np.ndarray, y: np.ndarray, nx: int, ny: int,
                   draws: int = SIMULATED_DRAWS, seed: int = SIMULATED_SEED) -> SimulatedNull:
    """The F ratio's null simulated for arms ``x``, ``y`` ((runs, bins), finite) with ``nx``,
    ``ny`` runs (more than measured: a prediction): each arm's runs normal with its measured
    per-bin variances and the bins' sample correlation (:func:`sample_correlation`); a
    draw is the bin differences' noise e and the sum of the bins' estimated variances (each
    arm's covariance eigenvalues times chi-square of its runs - 1 degrees of freedom). The
    distance sits along the observed difference of the mean profiles. A parametric
    bootstrap with a fixed seed: the same runs give the same draws. ``a_largest``: the
    same noise along the largest eigenvector (:meth:`SimulatedNull.largest`);
    ``a_fiducial``: along each draw's direction of the observed difference less a further,
    independent draw of the noise, drawn after the others so that they stay as they were
    (:meth:`SimulatedNull.fiducial`)."""
    sx, sy = x.var(axis=0, ddof=1), y.var(axis=0, ddof=1)
    corr = sample_correlation(x, y)
    cx, cy = corr * np.sqrt(np.outer(sx, sx)), corr * np.sqrt(np.outer(sy, sy))
    mu, u = _eig(cx / nx + cy / ny)
    lx, ly = _eig(cx)[0], _eig(cy)[0]
    rng = np.random.default_rng(seed)
    bins = x.shape[1]
    e = (rng.standard_normal((draws, bins)) * np.sqrt(mu)) @ u.T
    v = (rng.chisquare(nx - 1, (draws, bins)) @ lx / ((nx - 1) * nx)
         + rng.chisquare(ny - 1, (draws, bins)) @ ly / ((ny - 1) * ny))
    d = x.mean(axis=0) - y.mean(axis=0)
    norm = float(np.sqrt(np.sum(d * d)))
    direction = d / norm if norm > 0 else u[:, -1]
    total = float(np.sum(sx / nx + sy / ny))
    fiducial = d - (rng.standard_normal((draws, bins)) * np.sqrt(mu)) @ u.T
    lengths = np.sqrt(np.sum(fiducial * fiducial, axis=1))
    fiducial = np.where(lengths[:, None] > 0, fiducial / np.where(lengths > 0, lengths, 1.0
                                                                   )[:, None], u[:, -1])
    return SimulatedNull(e @ direction, np.sum(e * e, axis=1), v, float(np.sum(d * d)) / total,
                         e @ u[:, -1], np.sum(e * fiducial, axis=1))
