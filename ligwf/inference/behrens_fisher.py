"""The Behrens-Fisher distribution: the reference distribution of the difference of two
means whose arms have unequal, separately estimated variances, for arms of unequal size.

With d = mean(x) - mean(y), se_x^2 = s_x^2 / R_x, se_y^2 = s_y^2 / R_y and
tan(theta) = se_y / se_x, Fisher's fiducial argument gives (d - delta) / sqrt(se_x^2 + se_y^2)
~ cos(theta) T_1 - sin(theta) T_2, T_1 ~ t(R_x - 1) and T_2 ~ t(R_y - 1) independent. Its
quantiles make the interval of CG-n - CG1 where Welch-Satterthwaite's degrees of freedom are
liberal (6 runs against 2, 24 against 3: wrong pass 0.060-0.078, issue 45) and Hsu's
min(R_x, R_y) - 1 far too wide (two-sided coverage 0.999-1.000 at 6 against 2:
docs/results/verdict_rates); the test it makes is known to be conservative (Robinson 1976,
Ann. Stat. 4, 963), and ``benchmarks/bench_coverage.py --designs`` measures it.
"""

from __future__ import annotations

import math
from functools import lru_cache

import numpy as np
from scipy import optimize, special

#: Gauss-Legendre nodes on phi in (-pi/2, pi/2), T_2 = tan(phi): the integrand is smooth
#: there for every df (for df 1, T_2's density times dT_2 / dphi is constant)
_NODES, _WEIGHTS = np.polynomial.legendre.leggauss(256)
_PHI = 0.5 * math.pi * _NODES
_T2, _JAC = np.tan(_PHI), 0.5 * math.pi * _WEIGHTS / np.cos(_PHI) ** 2


def _t_pdf(t: np.ndarray, df: float) -> np.ndarray:
    log_norm = (special.gammaln(0.5 * (df + 1.0)) - special.gammaln(0.5 * df)
                - 0.5 * math.log(df * math.pi))
    return np.exp(log_norm - 0.5 * (df + 1.0) * np.log1p(t * t / df))


@lru_cache(maxsize=65536)
def cdf(z: float, theta: float, df1: float, df2: float) -> float:
    """P(cos(theta) T_1 - sin(theta) T_2 <= z)."""
    c, s = math.cos(theta), math.sin(theta)
    if c < 1e-9:
        return float(special.stdtr(df2, z))      # -T_2 is distributed as T_2
    if s < 1e-9:
        return float(special.stdtr(df1, z))
    inner = special.stdtr(df1, (z + s * _T2) / c)
    return float(min(1.0, max(0.0, np.sum(_JAC * _t_pdf(_T2, df2) * inner))))


@lru_cache(maxsize=8192)
def quantile(p: float, theta: float, df1: float, df2: float) -> float:
    """The ``p`` quantile of the Behrens-Fisher distribution at ``theta`` (radians)."""
    lo, hi = -1.0, 1.0
    while cdf(lo, theta, df1, df2) > p:
        lo *= 2.0
    while cdf(hi, theta, df1, df2) < p:
        hi *= 2.0
    return float(optimize.brentq(lambda z: cdf(z, theta, df1, df2) - p, lo, hi, xtol=1e-10))
