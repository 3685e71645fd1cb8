"""Field errors of a CG-n condition against CG1: the field criterion on what CG changes,
and the solid-fraction error.

* ``field_error`` -- the field criterion: the in-plane velocity in the drum frame, W = U -
  omega x r (the co-rotating plug has W = 0 at every CG level by construction, so only
  the flow that CG can change is compared), inside the flowing layer, normalised by the
  wall speed omega R. The layer is where the CG1 condition has material (phi_1 >=
  ``MATERIAL_SOLID``) and moves relative to the drum (|W_1| >= ``LAYER_SPEED`` omega R,
  the rigid-block share's tolerance: slower is co-rotating). Per run (its window mean is
  the unit of replication) the velocity at those nodes; between the arms' mean fields::

      D^2 = sum_x w(x) |mean_n W(x) - mean_1 W(x)|^2 / (omega R)^2,   w = phi_1 / sum phi_1

  a weighted RMS of the difference in units of the wall speed (the same as of U: omega x r
  cancels). Like the velocity profile it is corrected for the noise of both arms: the
  estimate is sqrt(max(0, D^2 - S)), S = sum w (s_n^2 / R_n + s_1^2 / R_1) / (omega R)^2
  the noise the run scatter puts into D^2. Bounds: by the triangle inequality the true
  distance lies within D +- |e|, e the noise; |e| <= t sqrt(S) with t Student's 1 - alpha / 2
  quantile at the Satterthwaite degrees of freedom of S taken as one component (the
  most correlated case, the widest), so each bound holds with probability >= 1 - alpha
  whatever the nodes' correlation (``tests/inference/test_field_criterion.py`` measures it).
  Reported at the kernel widths ``CRITERION_KERNELS`` (CG1 diameters); the verdict uses
  the study's ``analysis.field_kernel``.

* ``field_solid_error`` -- the solid-fraction field's relative L1 error over the whole
  cross-section: sum |phi_n - phi_1| / sum phi_1 (a bed that sits elsewhere or packs
  otherwise), with a frame-and-replica block-bootstrap interval (each replica's frames
  block-bootstrapped, block length from the autocorrelation of its per-frame mean speed,
  jointly with the CG1 reference's, replicas drawn with replacement; a resample of frames
  is a weighting of the recorded per-frame kernel sums, so a draw costs one matrix
  product) and its CG1 floor: with two or more CG1 replicas, each against the mean of the
  others (the largest); with one, the split-half error of that run divided by sqrt(2),
  labelled *indicative*.

CG1 against CG1 (:func:`null_split`): the field criterion between two halves of the CG1
runs -- half of the seeds against the other half when there are four or more, else the
first half of every run's window against the second half -- should be about 0: the null
check of the criterion and its noise correction.
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from typing import Callable

import numpy as np

from scipy import stats

from ligwf.inference.equivalence import ALPHA, NormEstimate, welch_df
from ligwf.analysis.records.fields import (CRITERION_KERNELS, EMPTY_SOLID, IN_PLANE,
                                           CaseFields, FieldGrid, WindowMeans)
from ligwf.analysis.records.intervals import (Interval, block_indices, block_length,
                                              interval_from_draws)
from ligwf.analysis.records.metrics import POSITIVE

#: a node where the CG1 solid fraction reaches this holds material (the field criterion's
#: support: the bed and its smoothed edge, not the dilute spray above it)
MATERIAL_SOLID = 0.1
#: a CG1 node moving relative to the drum at this share of omega R or more is in the
#: flowing layer (the rigid-block share's tolerance, ligwf.analysis.flow.frame.frame_flow)
LAYER_SPEED = 0.2
#: the field criterion at each width of CRITERION_KERNELS: column name per width
KERNEL_COLUMNS = {k: f"field_error_k{k:g}" for k in CRITERION_KERNELS}
#: the pieces of the verdict's field criterion's bounds (:class:`LayerNoise`), by column:
#: raw distance, per-run noise of the CG-n and the CG1 arm, and their numbers of runs
FIELD_NOISE_COLUMNS = ("field_error_distance", "field_error_run_var", "field_error_ref_var",
                       "field_error_runs", "field_error_ref_runs")
#: bootstrap draws evaluated at once (bounds the memory: draws x grid nodes x moments)
CHUNK = 100
#: the error columns this module computes, by name
FIELD_ERRORS = ("field_error", "field_solid_error")
NO_NORM = NormEstimate(math.nan, math.nan, math.nan, math.nan)

Error = Callable[[np.ndarray, np.ndarray], np.ndarray]


def solid_error(ref: np.ndarray, sums: np.ndarray) -> np.ndarray:
    """``field_solid_error``: sum |phi - phi_1| / sum phi_1 over all nodes."""
    phi1, phi = ref[..., 0, :, :], sums[..., 0, :, :]
    den = np.sum(phi1, axis=(-2, -1))
    with np.errstate(invalid="ignore", divide="ignore"):
        return np.where(den > 0, np.sum(np.abs(phi - phi1), axis=(-2, -1))
                        / np.where(den > 0, den, 1.0), np.nan)


#: the errors with a frame-bootstrap interval and a CG1 floor
ERRORS: dict[str, Error] = {"field_solid_error": solid_error}


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
                    names: tuple[str, ...] = tuple(ERRORS)) -> dict[str, Interval]:
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
    """One bootstrapped field error (``name`` in ``ERRORS``) with its interval
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


# ------------------------------------------------------------------ the field criterion
def rotation_velocity(grid: FieldGrid, omega: float) -> tuple[np.ndarray, np.ndarray]:
    """(u, v) components of the rigid rotation omega x r at the grid's nodes ((n, n) each,
    rows v, columns u), computed in 3-D as the rigid-block share does (the (u, v) plane
    of axis y is left-handed about +y)."""
    ia, iu, iv = grid.axis.frame
    e = np.eye(3)
    w = omega * e[ia]
    du, dv = np.cross(w, e[iu]), np.cross(w, e[iv])    # omega x r is linear in (u, v)
    c = grid.coordinates()
    uu, vv = np.meshgrid(c, c)
    return uu * du[iu] + vv * dv[iu], uu * du[iv] + vv * dv[iv]


def _velocity(sums: np.ndarray) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(phi, U, V) of in-plane kernel sums (..., 3, n, n); U, V nan where phi < EMPTY_SOLID."""
    phi = sums[..., 0, :, :]
    ok = phi >= EMPTY_SOLID
    safe = np.where(ok, phi, 1.0)
    return (phi, np.where(ok, sums[..., 1, :, :] / safe, np.nan),
            np.where(ok, sums[..., 2, :, :] / safe, np.nan))


@dataclass(frozen=True)
class LayerNoise:
    """What the field criterion's bounds are made of: the raw distance between the arms'
    mean fields (sqrt(D^2), units of omega R), each arm's per-run noise (sum_x w s^2 over
    its runs, units of (omega R)^2) and its number of runs. Its bounds at other run counts
    are what more replicas would give, the distance and the per-run scatter as measured
    (what would decide the criterion, :mod:`ligwf.inference.deciding`)."""

    distance: float
    run_variance: float
    reference_variance: float
    runs: int
    reference_runs: int

    def noise(self, add: tuple[int, int] = (0, 0)) -> tuple[float, float]:
        """(S, its Satterthwaite degrees of freedom) with ``add`` more runs per arm."""
        nx, ny = self.runs + add[0], self.reference_runs + add[1]
        return (self.run_variance / nx + self.reference_variance / ny,
                welch_df(self.run_variance, nx, self.reference_variance, ny))

    def half_width(self, alpha: float = ALPHA, add: tuple[int, int] = (0, 0)) -> float:
        """t sqrt(S): how far each bound lies from the raw distance."""
        noise, df = self.noise(add)
        t = float(stats.t.ppf(1.0 - alpha / 2.0, df)) if math.isfinite(df) else float(
            stats.norm.ppf(1.0 - alpha / 2.0))
        return t * math.sqrt(noise)

    def fail_p(self, tolerance: float) -> float:
        """The p-value of the criterion's fail test (H0: true distance <= ``tolerance``):
        the lower bound D - t sqrt(S) exceeds the tolerance at level alpha exactly when
        2 P(T >= (D - tolerance) / sqrt(S)) <= alpha (t is the 1 - alpha / 2 quantile);
        nan without the noise of both arms."""
        noise, df = self.noise()
        if not (math.isfinite(noise) and math.isfinite(tolerance)) or self.runs < 2 \
                or self.reference_runs < 2:
            return math.nan
        if noise <= 0:
            return 0.0 if self.distance > tolerance else 1.0
        z = (self.distance - tolerance) / math.sqrt(noise)
        tail = float(stats.t.sf(z, df)) if math.isfinite(df) else float(stats.norm.sf(z))
        return min(1.0, 2.0 * tail)

    def estimate(self, alpha: float = ALPHA) -> NormEstimate:
        """The noise-corrected distance and its bounds (module docstring)."""
        noise, _ = self.noise()
        half = self.half_width(alpha)
        value = math.sqrt(max(0.0, self.distance ** 2 - noise))
        return NormEstimate(value, max(0.0, self.distance - half), self.distance + half,
                            self.distance)


def layer_noise(runs: np.ndarray, reference: np.ndarray, weights: np.ndarray,
                scale: float) -> LayerNoise | None:
    """The pieces of the field criterion (:class:`LayerNoise`) of two arms' vector
    fields: ``runs`` (R_n, C, K) and ``reference`` (R_1, C, K), per run C components at K
    nodes; ``weights`` (K,) >= 0. None when the shapes or the weights do not fit; nan
    variances with fewer than two runs in an arm."""
    x, y = np.asarray(runs, float), np.asarray(reference, float)
    w = np.asarray(weights, float)
    if (x.ndim != 3 or y.ndim != 3 or x.shape[1:] != y.shape[1:] or not len(x) or not len(y)
            or w.shape != x.shape[2:] or not np.sum(w) > 0 or not scale > 0):
        return None
    w = w / np.sum(w)
    d = x.mean(axis=0) - y.mean(axis=0)                                  # (C, K)
    distance = math.sqrt(float(np.sum(w * d * d))) / scale

    def per_run(a: np.ndarray) -> float:
        return (float(np.sum(w * a.var(axis=0, ddof=1))) / scale ** 2 if len(a) > 1
                else math.nan)

    return LayerNoise(distance, per_run(x), per_run(y), len(x), len(y))


def layer_norm(runs: np.ndarray, reference: np.ndarray, weights: np.ndarray, scale: float,
               alpha: float = ALPHA) -> NormEstimate:
    """The noise-corrected weighted RMS distance between two arms' mean vector fields, in
    units of ``scale`` (module docstring; arrays as :func:`layer_noise`). Without two runs
    in each arm: the raw distance and no bounds."""
    noise = layer_noise(runs, reference, weights, scale)
    if noise is None:
        return NO_NORM
    if noise.runs < 2 or noise.reference_runs < 2:
        return NormEstimate(noise.distance, math.nan, math.nan, noise.distance)
    return noise.estimate(alpha)


def _means(cases: list[CaseFields], kernel: float) -> list[WindowMeans] | None:
    means = [c.at_kernel(kernel) for c in cases]
    return None if any(m is None for m in means) else means


def _one_grid(means: list[WindowMeans]) -> bool:
    return len({(m.grid.origin, m.grid.spacing, m.grid.nodes, m.grid.axis)
                for m in means}) == 1


def _layer_arrays(cases: list[tuple[CaseFields, str]], refs: list[tuple[CaseFields, str]],
                  kernel: float):
    """(runs, reference, weights, omega R) of the field criterion (arrays as
    :func:`layer_noise`), or None (see :func:`layer_error`)."""
    if not cases or not refs:
        return None
    cm = _means([c for c, _ in cases], kernel)
    rm = _means([c for c, _ in refs], kernel)
    if cm is None or rm is None or not _one_grid(cm + rm):
        return None
    omega, radius = refs[0][0].omega, refs[0][0].radius
    scale = abs(omega) * radius
    if not (math.isfinite(scale) and scale > 0):
        return None
    x = np.stack([m.part(p) for m, (_, p) in zip(cm, cases)])           # (R, 3, n, n)
    y = np.stack([m.part(p) for m, (_, p) in zip(rm, refs)])
    grid = rm[0].grid
    ru, rv = rotation_velocity(grid, omega)
    phi1, u1, v1 = _velocity(y.mean(axis=0))
    _, xu, xv = _velocity(x)
    _, yu, yv = _velocity(y)
    with np.errstate(invalid="ignore"):
        moving = np.hypot(u1 - ru, v1 - rv) >= LAYER_SPEED * scale
    layer = ((phi1 >= MATERIAL_SOLID) & moving & np.isfinite(xu).all(axis=0)
             & np.isfinite(yu).all(axis=0))
    if not layer.any():
        return None
    runs = np.stack([xu[:, layer], xv[:, layer]], axis=1)                 # (R, 2, K)
    ref = np.stack([yu[:, layer], yv[:, layer]], axis=1)
    return runs, ref, phi1[layer], scale


def layer_error(cases: list[tuple[CaseFields, str]], refs: list[tuple[CaseFields, str]],
                kernel: float, alpha: float = ALPHA) -> NormEstimate:
    """The field criterion of the runs ``cases`` against the CG1 runs ``refs`` at
    ``kernel`` CG1 diameters; each run a (case, part of its window: ``WINDOW_PARTS``).
    nan when a run lacks the window means (an analysis from before them), the grids
    differ, the drum's omega R is unknown or there is no flowing layer."""
    arrays = _layer_arrays(cases, refs, kernel)
    return NO_NORM if arrays is None else layer_norm(*arrays, alpha=alpha)


def layer_components(cases: list[tuple[CaseFields, str]], refs: list[tuple[CaseFields, str]],
                     kernel: float) -> LayerNoise | None:
    """The pieces of :func:`layer_error`'s bounds (None where it is nan)."""
    arrays = _layer_arrays(cases, refs, kernel)
    return None if arrays is None else layer_noise(*arrays)


def whole_windows(cases: list[CaseFields]) -> list[tuple[CaseFields, str]]:
    """Each case as one run: its whole steady window."""
    return [(c, "window") for c in cases]


def null_split(refs: list[CaseFields]) -> tuple[list, list, str]:
    """Two arms of CG1 runs for the CG1-vs-CG1 null check, and how they were split: half
    of the seeds against the other half with four or more, else the first half of every
    run's window against the second half (halves of one run are closer than two seeds,
    so this null check is lenient)."""
    if len(refs) >= 4:
        half = len(refs) // 2
        return (whole_windows(refs[:half]), whole_windows(refs[half:]),
                f"CG1 seeds {half} against {len(refs) - half}")
    return ([(c, "first_half") for c in refs], [(c, "second_half") for c in refs],
            f"first against second half of the window of {len(refs)} CG1 run(s)")
