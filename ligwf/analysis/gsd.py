"""Granule size distributions (GSD) and their comparison across CG levels.

Sizes are *primary-particle-equivalent volumes* (m^3): a CG-n granule's volume / n^3, the
volume of original particles it stands for, so CG-n and CG1 distributions share one axis.
Distributions are histograms on logarithmic bins of that volume, per frame:

* number-weighted: share of granules in each bin;
* volume-weighted: share of the bed volume held by granules in each bin (what sieving
  measures, and what d10/d50/d90 refer to).

Time averages are means of the per-frame distributions. Confidence bands come from a
hierarchical bootstrap: resample replicas, then frames within each drawn replica (frames
are dump_interval apart and treated as independent samples; with one replica only frames
are resampled). Every random draw comes from one seeded generator, so results are
reproducible and identical in serial and MPI runs.

CG comparison: the volume-weighted GSD of CG-n against CG1, per-bin relative error, and
the error summed below and above a *size limit*: the primary-equivalent volume of
``min_particles`` CG-n particles. A CG-n granule smaller than that is made of fewer than
``min_particles`` particles, so its size is resolved in steps of one whole CG particle
(n^3 primary particles) and CG cannot reproduce the fine end of the GSD; above it, it can.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import dataclass

import numpy as np

#: Default particle count below which a CG granule is too coarse to resolve its size:
#: with 10 members, one particle more or less changes the volume by 10% (the width of a
#: bin at 5 bins per decade is ~58%, so below ~10 members bins are sampled in holes).
DEFAULT_MIN_PARTICLES = 10


@dataclass(frozen=True)
class GsdSettings:
    """Binning, size-limit and bootstrap settings of the GSD stage."""

    bins_per_decade: int = 5
    min_particles: int = DEFAULT_MIN_PARTICLES
    n_boot: int = 1000
    confidence: float = 0.95
    seed: int = 12345

    def __post_init__(self) -> None:
        if self.bins_per_decade < 1:
            raise ValueError(f"bins_per_decade = {self.bins_per_decade}: must be >= 1")
        if self.min_particles < 1:
            raise ValueError(f"min_particles = {self.min_particles}: must be >= 1")
        if self.n_boot < 1:
            raise ValueError(f"n_boot = {self.n_boot}: must be >= 1")
        if not 0.0 < self.confidence < 1.0:
            raise ValueError(f"confidence = {self.confidence}: allowed range (0, 1)")


def log_edges(v_min: float, v_max: float, per_decade: int) -> np.ndarray:
    """Logarithmic bin edges (m^3) covering [v_min, v_max].

    Bins are decade-aligned (centres at 10^(k / per_decade)), so studies and CG levels
    always bin alike whatever their smallest and largest granule.
    """
    if not (v_min > 0 and v_max >= v_min):
        raise ValueError(f"bin range [{v_min}, {v_max}] m^3: need 0 < v_min <= v_max")
    lo = math.floor(math.log10(v_min) * per_decade - 0.5) + 0.5
    hi = max(lo + 1.0, math.ceil(math.log10(v_max) * per_decade - 0.5) + 0.5)
    return 10.0 ** (np.arange(lo, hi + 0.25, 1.0) / per_decade)


def histogram(volumes: np.ndarray, edges: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Number and volume fractions per bin of one frame's granule volumes (m^3).

    Volumes outside the edges are counted in the end bins (edges normally cover them).
    """
    idx = np.clip(np.searchsorted(edges, volumes, side="right") - 1, 0, len(edges) - 2)
    nb = len(edges) - 1
    count = np.bincount(idx, minlength=nb).astype(float)
    vol = np.bincount(idx, weights=volumes, minlength=nb)
    return count / max(count.sum(), 1.0), vol / (vol.sum() if vol.sum() > 0 else 1.0)


def percentile_diameters(volumes: np.ndarray, fractions=(0.1, 0.5, 0.9)) -> np.ndarray:
    """d10, d50, d90 (m): equivalent-sphere diameters of the volume-weighted GSD.

    d_q is the diameter of the smallest granule such that granules up to it hold at least
    the fraction q of the total volume (no interpolation: well defined for any frame).
    """
    v = np.sort(np.asarray(volumes, dtype=float))
    cum = np.cumsum(v) / v.sum()
    k = np.searchsorted(cum, np.asarray(fractions) - 1e-12, side="left")
    return np.cbrt(6.0 * v[np.minimum(k, len(v) - 1)] / math.pi)


def size_limit(particle_primary_volume: float, min_particles: int) -> float:
    """Primary-equivalent volume (m^3) of a granule of ``min_particles`` CG particles."""
    return float(min_particles) * float(particle_primary_volume)


def _resample_indices(replicas: np.ndarray, rng: np.random.Generator) -> np.ndarray:
    """One hierarchical bootstrap draw: replicas with replacement, then frames in each."""
    groups = [np.nonzero(replicas == r)[0] for r in np.unique(replicas)]
    if len(groups) > 1:
        groups = [groups[k] for k in rng.integers(len(groups), size=len(groups))]
    return np.concatenate([g[rng.integers(len(g), size=len(g))] for g in groups])


def bootstrap_means(per_frame: np.ndarray, replicas: np.ndarray, n_boot: int,
                    rng: np.random.Generator) -> np.ndarray:
    """(n_boot, bins) means of hierarchically resampled per-frame rows."""
    per_frame = np.asarray(per_frame, dtype=float)
    return np.stack([per_frame[_resample_indices(replicas, rng)].mean(axis=0)
                     for _ in range(n_boot)])


def band(draws: np.ndarray, confidence: float) -> tuple[np.ndarray, np.ndarray]:
    """Lower and upper percentile band of bootstrap draws (nan-aware)."""
    a = 50.0 * (1.0 - confidence)
    with np.errstate(all="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)   # all-nan bins give nan, quietly
        return np.nanpercentile(draws, a, axis=0), np.nanpercentile(draws, 100.0 - a, axis=0)


def relative_error(cg: np.ndarray, ref: np.ndarray) -> np.ndarray:
    """(cg - ref) / ref per bin; nan where the reference bin is empty."""
    with np.errstate(divide="ignore", invalid="ignore"):
        return np.where(ref > 0, (cg - ref) / np.where(ref > 0, ref, 1.0), np.nan)


def side_errors(cg: np.ndarray, ref: np.ndarray, below: np.ndarray) -> tuple[float, float]:
    """Relative L1 error of the volume-weighted GSD below and above the size limit:
    sum |cg - ref| / sum ref over the bins on each side (nan if the reference has none)."""
    out = []
    for side in (below, ~below):
        total = ref[..., side].sum(axis=-1)
        diff = np.abs(cg[..., side] - ref[..., side]).sum(axis=-1)
        with np.errstate(divide="ignore", invalid="ignore"):
            out.append(np.where(total > 0, diff / np.where(total > 0, total, 1.0), np.nan))
    return out[0], out[1]


def below_limit(edges: np.ndarray, limit: float) -> np.ndarray:
    """Bins whose geometric centre lies below the size limit."""
    return np.sqrt(edges[:-1] * edges[1:]) < limit
