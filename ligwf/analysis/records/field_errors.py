"""Field errors of a CG-n condition against CG1, their 95 % interval and their CG1 floor.

Definitions (of window-mean fields, :func:`ligwf.analysis.records.fields.fields_of`; a
condition's fields are those of the mean over its replicas of their window-mean kernel
sums):

* ``field_error`` -- the velocity field's relative L2 error, weighted by the CG1 solid
  fraction, over the nodes where CG1 has material (phi_1 >= ``MATERIAL_SOLID``) and the
  CG-n condition has any (phi_n >= EMPTY_SOLID)::

      sqrt( sum phi_1 |U_n - U_1|^2 / sum phi_1 |U_1|^2 )      U = (u, v), in-plane

* ``field_solid_error`` -- the solid-fraction field's relative L1 error over the whole
  cross-section: sum |phi_n - phi_1| / sum phi_1 (a bed that sits elsewhere or packs
  otherwise).

Interval: as every error against CG1 (:mod:`ligwf.analysis.records.intervals`): each
replica's frames are block-bootstrapped (block length from the autocorrelation of its
per-frame mean speed) jointly with the CG1 reference's, replicas drawn with replacement,
widened for few replicas, never narrower than the within-run error, none for one CG-n
replica. A resample of frames is a weighting of the recorded per-frame kernel sums, so a
draw costs one matrix product, not a re-analysis.

Floor (how far CG1 is from CG1): with two or more CG1 replicas, each against the mean of
the others (the largest); with one, the split-half error of that run (first half of its
window against the second) divided by sqrt(2) -- two half windows differ by sqrt(2) more
than two full windows when the difference is noise -- and labelled *indicative*, as the
other floors from one run are.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from ligwf.analysis.records.fields import EMPTY_SOLID, CaseFields
from ligwf.analysis.records.intervals import (Interval, block_indices, block_length,
                                              interval_from_draws)
from ligwf.analysis.records.metrics import POSITIVE

#: a node where the CG1 solid fraction reaches this holds material (the velocity error's
#: support: the bed and its smoothed edge, not the dilute spray above it)
MATERIAL_SOLID = 0.1
#: bootstrap draws evaluated at once (bounds the memory: draws x grid nodes x moments)
CHUNK = 100
#: the errors read the first moments only: solid fraction, flux u, flux v
IN_PLANE = 3
#: the error columns this module computes, by name
FIELD_ERRORS = ("field_error", "field_solid_error")

Error = Callable[[np.ndarray, np.ndarray], np.ndarray]


def _in_plane(sums: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(phi, u, v) of kernel sums (u, v 0 where phi < EMPTY_SOLID): what the velocity
    error needs, without the other fields."""
    phi = sums[..., 0, :, :]
    ok = phi >= EMPTY_SOLID
    inv = np.where(ok, 1.0 / np.where(ok, phi, 1.0), 0.0)
    return phi, sums[..., 1, :, :] * inv, sums[..., 2, :, :] * inv


def velocity_error(ref: np.ndarray, sums: np.ndarray) -> np.ndarray:
    """``field_error`` of kernel sums ``sums`` against ``ref`` (both ``(..., moments, n,
    n)``, broadcasting over leading draw axes); nan without a common material node."""
    phi1, u1, v1 = _in_plane(ref)
    phi, u, v = _in_plane(sums)
    weight = np.where((phi1 >= MATERIAL_SOLID) & (phi >= EMPTY_SOLID), phi1, 0.0)
    num = np.sum(weight * ((u - u1) ** 2 + (v - v1) ** 2), axis=(-2, -1))
    den = np.sum(weight * (u1**2 + v1**2), axis=(-2, -1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, np.sqrt(num / np.where(den > 0, den, 1.0)), np.nan)


def solid_error(ref: np.ndarray, sums: np.ndarray) -> np.ndarray:
    """``field_solid_error``: sum |phi - phi_1| / sum phi_1 over all nodes."""
    phi1, phi = ref[..., 0, :, :], sums[..., 0, :, :]
    den = np.sum(phi1, axis=(-2, -1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, np.sum(np.abs(phi - phi1), axis=(-2, -1))
                        / np.where(den > 0, den, 1.0), np.nan)


ERRORS: dict[str, Error] = {"field_error": velocity_error, "field_solid_error": solid_error}


def same_grid(cases: list[CaseFields]) -> bool:
    """Whether the cases' fields are on one grid (one drum, one kernel): only then do
    they compare node by node."""
    grids = {(c.grid.origin, c.grid.spacing, c.grid.nodes, c.grid.width, c.grid.axis)
             for c in cases}
    return len(grids) <= 1


def condition_mean(cases: list[CaseFields]) -> np.ndarray:
    """The condition's kernel sums: the mean over replicas of their window means."""
    return np.mean([c.mean() for c in cases], axis=0)


def _weights(case: CaseFields, draws: int, rng: np.random.Generator) -> np.ndarray:
    """(draws, F) frame weights of moving-block resamples of the case's frames."""
    n = case.frames
    idx = block_indices(n, block_length(case.speed_signal()), draws, rng)
    w = np.zeros((draws, n))
    np.add.at(w, (np.arange(draws)[:, None], idx), 1.0 / n)
    return w


def _resampled(case: CaseFields, w: np.ndarray) -> np.ndarray:
    """(draws, moments, n, n) kernel sums of the frame weightings ``w``."""
    flat = case.moments.reshape(case.frames, -1)
    return (w @ flat).reshape((len(w),) + case.moments.shape[1:])


def _condition_draws(cases: list[CaseFields], draws: int, rng: np.random.Generator
                     ) -> tuple[np.ndarray, np.ndarray]:
    """(combined, within) draws of a condition's kernel sums: replicas with replacement
    and frames resampled; every replica once and frames resampled."""
    per = np.stack([_resampled(c, _weights(c, draws, rng)) for c in cases])   # (R, D, ...)
    pick = rng.integers(0, len(cases), size=(draws, len(cases)))
    combined = per[pick, np.arange(draws)[:, None]].mean(axis=1)
    return combined, per.mean(axis=0)


def _material_only(cases: list[CaseFields]) -> list[CaseFields]:
    """The cases with only what the errors read: the solid fraction and the in-plane
    fluxes (``IN_PLANE`` moments) on the nodes where any of them ever has material, as a
    1 x K grid. The errors are the same (a node without material in every case adds
    nothing to either sum) and the bootstrap draws a fraction of the size."""
    keep = np.any([c.moments[:, 0].max(axis=0) > 0 for c in cases], axis=0)
    return [dataclasses.replace(c, moments=c.moments[:, :IN_PLANE][:, :, keep][:, :, None, :])
            for c in cases]


def field_intervals(cases: list[CaseFields], refs: list[CaseFields], draws: int, seed: int,
                    names: tuple[str, ...] = FIELD_ERRORS) -> dict[str, Interval]:
    """Each field error ``names`` of a condition's replicas ``cases`` against the CG1
    replicas ``refs``, with its 95 % interval (module docstring; one set of draws for all
    of them); nan without cases, references or a common grid."""
    cases = [c for c in cases if c.frames]
    refs = [c for c in refs if c.frames]
    if not cases or not refs or not same_grid(cases + refs):
        return {n: Interval(math.nan, math.nan, math.nan, math.nan, len(cases)) for n in names}
    values = {n: float(ERRORS[n](condition_mean(refs), condition_mean(cases))) for n in names}
    reduced = _material_only(cases + refs)
    cases, refs = reduced[:len(cases)], reduced[len(cases):]
    rng = np.random.default_rng(seed)
    comb: dict[str, list] = {n: [] for n in names}
    within: dict[str, list] = {n: [] for n in names}
    for start in range(0, draws, CHUNK):
        k = min(CHUNK, draws - start)
        c_comb, c_within = _condition_draws(cases, k, rng)
        r_comb, r_within = _condition_draws(refs, k, rng)
        if len(refs) < 2:
            r_comb = r_within
        for n in names:
            comb[n].append(ERRORS[n](r_comb, c_comb))
            within[n].append(ERRORS[n](r_within, c_within))
    return {n: interval_from_draws(values[n], np.concatenate(comb[n]),
                                   np.concatenate(within[n]), len(cases), POSITIVE)
            for n in names}


def field_interval(cases: list[CaseFields], refs: list[CaseFields], name: str, draws: int,
                   seed: int) -> Interval:
    """One field error (``name`` in ``FIELD_ERRORS``) with its interval
    (:func:`field_intervals`)."""
    return field_intervals(cases, refs, draws, seed, (name,))[name]


@dataclass(frozen=True)
class FieldFloor:
    """CG1-vs-CG1 floor of a field error (``source`` as the other floors word it)."""

    value: float
    source: str


def split_half(case: CaseFields) -> tuple[np.ndarray, np.ndarray]:
    """The window-mean kernel sums of the first and the second half of a run's frames."""
    half = case.frames // 2
    return case.moments[:half].mean(axis=0), case.moments[half:].mean(axis=0)


def field_floor(refs: list[CaseFields], name: str) -> FieldFloor:
    """The CG1 floor of a field error from the CG1 replicas ``refs`` (module docstring)."""
    error = ERRORS[name]
    refs = [c for c in refs if c.frames]
    if not refs or not same_grid(refs):
        return FieldFloor(math.nan, "none")
    if len(refs) >= 2:
        means = [c.mean() for c in refs]
        errs = [float(error(np.mean(means[:k] + means[k + 1:], axis=0), means[k]))
                for k in range(len(refs))]
        return FieldFloor(float(np.nanmax(errs)), f"measured over {len(refs)} CG1 replicas")
    if refs[0].frames < 4:
        return FieldFloor(math.nan, "none: fewer than 4 steady frames in the CG1 run")
    first, second = split_half(refs[0])
    return FieldFloor(float(error(first, second)) / math.sqrt(2.0),
                      "indicative: split-half of 1 CG1 run (within-run noise)")
