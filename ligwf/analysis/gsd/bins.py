"""Granule size distributions (GSD) and their comparison across CG levels.

Sizes are granule volumes (m^3) -- physical, NOT divided by n^3: a CG-n bed holds the
same solid volume as the CG1 bed, and a CG-neutral granule definition (the default CPM
communities, :mod:`ligwf.analysis.granules.definitions`) gives the same granule volumes at every
level (measured CG2/CG1 d50 = 1.00), so CG-n and CG1 share one axis. (The granule table
keeps ``primary_volume`` = volume / n^3 for whoever wants that convention; under it the
same physical granule looks n^3 smaller at CG-n.) Only granules of at least
``min_particles`` particles that do not percolate (close a cycle around the periodic
axis: a bed-spanning cluster, reported on its own) enter the GSD. Distributions are
histograms on logarithmic bins, per frame:

* number-weighted: share of granules in each bin;
* volume-weighted: share of the granule volume held by granules in each bin (what
  sieving measures, and what d10/d50/d90 refer to).

Time averages are means of the per-frame distributions. Confidence bands come from a
hierarchical bootstrap: resample replicas, then frames within each drawn replica in moving
blocks (frames are dump_interval apart and correlated over a few frames: the block is 2x
the measured autocorrelation time of the replica's series, the largest over its columns,
:func:`ligwf.analysis.records.intervals.block_length`; treating frames as independent made bands
1.4-2.2x too narrow). With one replica only frames are resampled. Every random draw comes from one seeded generator, so results are
reproducible and identical in serial and MPI runs.

CG comparison: the volume-weighted GSD of CG-n against CG1, per-bin relative error, and
the error summed below and above a *size limit located from the data*
(:func:`located_limit`): the smallest granule volume from which on every populated bin of
CG-n stays within ``error_band`` (default 15 %) of CG1. Below it CG-n leaves the band
(its granules are resolved in steps of whole CG particles, n^3 primaries each); the limit
gets its own bootstrap interval from the same draws as the bands.
"""

from __future__ import annotations

import math
import warnings

import numpy as np

from ligwf.scene.settings import AnalysisSettings

#: Bins holding less than this share of the CG1 granule volume are too sparsely sampled
#: for a relative error (a handful of granules): they do not move the located limit.
MIN_BIN_SHARE = 0.01


#: analysis.gsd_volume -> the granule-table column the GSD bins
VOLUME_COLUMNS = {"physical": "volume", "primary": "primary_volume"}


#: confidence of the GSD bootstrap bands (the binning, bootstrap draws, seed, size-limit
#: band and smallest granule are the study's AnalysisSettings, read as they are)
CONFIDENCE = 0.95


def volume_column(settings: AnalysisSettings) -> str:
    """The granule-table column the GSD of ``settings`` bins (its ``gsd_volume``)."""
    return VOLUME_COLUMNS[settings.gsd_volume]


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
    if len(v) == 0 or v.sum() <= 0:
        return np.full(len(fractions), np.nan)
    cum = np.cumsum(v) / v.sum()
    k = np.searchsorted(cum, np.asarray(fractions) - 1e-12, side="left")
    return np.cbrt(6.0 * v[np.minimum(k, len(v) - 1)] / math.pi)


def band_misses(cg: np.ndarray, ref: np.ndarray, error_band: float,
                min_share: float = MIN_BIN_SHARE) -> list[tuple[np.ndarray, np.ndarray]]:
    """Per row of ``cg`` / ``ref`` (volume-weighted GSDs, (..., bins)): the used bins (those
    holding at least ``min_share`` of the CG1 volume) and, for each, whether
    |cg - ref| > ``error_band`` x ref -- the test both size limits read (this one and
    :func:`ligwf.analysis.gsd.pooling.upper_limit`)."""
    out = []
    for c, f in zip(np.atleast_2d(cg), np.atleast_2d(ref)):
        used = np.flatnonzero(f >= min_share)
        out.append((used, np.abs(c[used] - f[used]) > error_band * f[used]))
    return out


def located_limit(edges: np.ndarray, cg: np.ndarray, ref: np.ndarray, error_band: float,
                  min_share: float = MIN_BIN_SHARE) -> np.ndarray:
    """Size limit (m^3) located from the data, per row of ``cg`` / ``ref`` (volume-weighted
    GSDs, (..., bins)): the lower edge of the smallest bin from which on every bin holding
    at least ``min_share`` of the CG1 volume has |cg - ref| / ref <= ``error_band``; nan
    when the largest such bin is outside the band (CG-n never enters it)."""
    misses = band_misses(cg, ref, error_band, min_share)
    out = np.full(len(misses), np.nan)
    for r, (used, bad) in enumerate(misses):
        if len(used) == 0 or bad[-1]:
            continue
        first_ok = used[np.flatnonzero(bad)[-1] + 1] if bad.any() else used[0]
        out[r] = edges[first_ok]
    return out if np.ndim(cg) > 1 else out[0]


def block_lengths(per_frame: np.ndarray, replicas: np.ndarray) -> list[int]:
    """Moving-block length per replica (in ``np.unique`` order): the largest
    :func:`~ligwf.analysis.records.intervals.block_length` over the columns of its frames (rows in
    time order)."""
    from ligwf.analysis.records.intervals import block_length

    per_frame = np.asarray(per_frame, dtype=float).reshape(len(replicas), -1)
    return [max(block_length(col) for col in per_frame[replicas == r].T)
            for r in np.unique(replicas)]


def _resample_indices(replicas: np.ndarray, rng: np.random.Generator,
                      blocks: list[int] | None = None) -> np.ndarray:
    """One hierarchical bootstrap draw: replicas with replacement, then frames in each in
    moving blocks of ``blocks[k]`` frames (1: frames independently)."""
    from ligwf.analysis.records.intervals import block_indices

    groups = [np.nonzero(replicas == r)[0] for r in np.unique(replicas)]
    blocks = blocks or [1] * len(groups)
    pick = (rng.integers(len(groups), size=len(groups)) if len(groups) > 1
            else np.zeros(1, dtype=np.int64))
    return np.concatenate([groups[k][block_indices(len(groups[k]), blocks[k], 1, rng)[0]]
                           for k in pick])


def bootstrap_means(per_frame: np.ndarray, replicas: np.ndarray, n_boot: int,
                    rng: np.random.Generator) -> np.ndarray:
    """(n_boot, bins) means of hierarchically block-resampled per-frame rows (rows of one
    replica in time order)."""
    per_frame = np.asarray(per_frame, dtype=float)
    replicas = np.asarray(replicas)
    blocks = block_lengths(per_frame, replicas) if len(per_frame) else None
    with warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)   # frames without a granule: nan
        return np.stack([np.nanmean(per_frame[_resample_indices(replicas, rng, blocks)], axis=0)
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
    """Bins whose geometric centre lies below the size limit (every bin when the limit is
    nan: CG-n never enters the error band)."""
    if not np.isfinite(limit):
        return np.ones(len(edges) - 1, dtype=bool)
    return np.sqrt(edges[:-1] * edges[1:]) < limit


def counted(members: np.ndarray, percolating: np.ndarray, min_particles: int) -> np.ndarray:
    """Granules that enter the GSD: >= ``min_particles`` members and not percolating."""
    return (np.asarray(members) >= min_particles) & ~np.asarray(percolating, dtype=bool)


def frame_stats(volume: np.ndarray, members: np.ndarray, percolating: np.ndarray,
                min_particles: int) -> dict[str, float]:
    """One frame's granule numbers: count, d10/d50/d90 (m, volume-equivalent, of the
    counted granules), largest counted granule, bed share in counted granules and bed
    share in percolating granules (shares of the whole bed's solid volume)."""
    volume = np.asarray(volume, dtype=float)
    keep = counted(members, percolating, min_particles)
    bed = volume.sum()
    v = volume[keep]
    d10, d50, d90 = percentile_diameters(v)
    return {"granules": float(keep.sum()), "d10": d10, "d50": d50, "d90": d90,
            "largest_granule": float(v.max() / bed) if len(v) else 0.0,
            "granule_share": float(v.sum() / bed) if bed > 0 else 0.0,
            "percolating_share": float(volume[np.asarray(percolating, bool)].sum() / bed)
            if bed > 0 else 0.0}
