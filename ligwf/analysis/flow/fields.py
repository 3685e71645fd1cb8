"""Coarse-grained continuum fields on the drum cross-section, over the steady window.

The fields the source study's companion work compares between CG levels: the solid
fraction phi, the mean in-plane velocity (u, v) and the granular temperature T, on a
square grid of the cross-section (the plane normal to the drum axis, coordinates u
horizontal and v up as in :mod:`ligwf.analysis.flow.frame`), averaged along the periodic
axis and over the frames of the steady window.

Coarse graining (Goldhirsch; Weinhart et al. 2012): particle i (volume V_i, centre x_i,
velocity c_i) contributes through a 2-D Gaussian kernel K of standard deviation ``width``
(m), cut at ``KERNEL_CUTOFF`` widths and normalised to unit area::

    phi(x)       = sum_i V_i K(x - x_i) / L                 (solid fraction)
    phi u(x)     = sum_i V_i c_i K(x - x_i) / L             (volume flux; one material
                                                             density, so volume weights are
                                                             mass weights)
    3 phi T(x)   = sum_i V_i |c_i - u(x_i)|^2 K(x - x_i) / L

with L the periodic length. The kernel width is a physical length, the same at every CG
level (:attr:`ligwf.scene.settings.AnalysisSettings.field_kernel` CG1 particle diameters),
so a CG-n field and the CG1 field are smoothed alike and compare cell by cell. The
fluctuation is taken about the steady-window mean field at the particle's own position
(bilinear from the grid): a rigid rotation has T = 0 exactly, not the (omega width)^2 a
fluctuation about the field point's velocity would give.

Fast path: each frame's particles are deposited on the grid nodes with cloud-in-cell
weights (exact for the first moment), then the node sums are convolved with the sampled
Gaussian along each axis (separable). The effective kernel is the Gaussian convolved with
the cloud-in-cell tent: its standard deviation is sqrt(width^2 + h^2 / 6) = 1.02 width for
the grid spacing h = width / ``CELLS_PER_WIDTH``. Cost: O(particles) per frame (a
360k-particle frame takes well under a second). :func:`reference_moments` evaluates the
kernel sums directly (every particle on every node) for the tests.

Near the drum wall the kernel reaches where no particle can be, so the fields there are
smoothed towards zero (the usual boundary effect of a kernel; the same at every CG level,
as the width is), and kernel weight beyond the node square is dropped: on the demo drum
96-99 % of the bed's volume is on the grid.

The per-frame sums are kept (:class:`~ligwf.analysis.records.fields.CaseFields`): the
solid-fraction error's interval resamples them (:mod:`ligwf.inference.field_errors`).
Beside them, at each width of ``CRITERION_KERNELS`` CG1 diameters, the window means of the
in-plane sums (whole window and its two halves) and the drum's omega and radius: the field
criterion compares runs by these.
"""

from __future__ import annotations

import math

import numpy as np
from scipy import ndimage

from ligwf.analysis.flow.frame import DrumGeometry
from ligwf.analysis.frames.dumps import ParticleFrame
from ligwf.analysis.records.fields import (CRITERION_KERNELS, IN_PLANE, CaseFields, FieldGrid,
                                           WindowMeans)
from ligwf.scene.axis import Axis

#: the Gaussian is cut at this many standard deviations (and renormalised)
KERNEL_CUTOFF = 3.0
#: grid nodes per kernel width
CELLS_PER_WIDTH = 2
#: at most this many nodes per axis (a large drum with a narrow kernel gets a coarser
#: grid: the same kernel, sampled more coarsely, so the effective width grows a little)
MAX_NODES = 512


def field_grid(geo: DrumGeometry, width: float, length: float) -> FieldGrid:
    """The node grid of a drum's cross-section: spacing ``width / CELLS_PER_WIDTH``, nodes
    covering [-R, R] on both axes, centred on the drum axis (``length``: the periodic
    length the fields are averaged over, m)."""
    if not (math.isfinite(width) and width > 0):
        raise ValueError(f"kernel width {width!r} m: must be a positive length")
    h = max(width / CELLS_PER_WIDTH, 2.0 * geo.radius / (MAX_NODES - 1))
    n = min(int(math.ceil(2.0 * geo.radius / h)) + 1, MAX_NODES)
    origin = -0.5 * (n - 1) * h
    return FieldGrid(origin=origin, spacing=h, nodes=n, width=width, length=length,
                     axis=geo.axis)


def kernel_width(geo: DrumGeometry, cg: float, field_kernel: float) -> float:
    """The kernel width in m: ``field_kernel`` CG1 mean diameters (the case's mean
    diameter over its CG level), the same physical length at every CG level."""
    return field_kernel * geo.d_mean / cg


def kernel_weights(grid: FieldGrid) -> np.ndarray:
    """The 1-D Gaussian sampled on the nodes within the cut-off, normalised so that the
    2-D kernel (outer product) sums to one per unit area (sum g h = 1 per axis)."""
    reach = int(math.floor(KERNEL_CUTOFF * grid.width / grid.spacing))
    x = np.arange(-reach, reach + 1) * grid.spacing
    g = np.exp(-0.5 * (x / grid.width) ** 2)
    return g / (g.sum() * grid.spacing)


def _in_plane(frame: ParticleFrame, axis: Axis) -> tuple[np.ndarray, np.ndarray, np.ndarray]:
    """(u, v) of every particle and its velocity (u, v, axial components) in that order."""
    ia, iu, iv = axis.frame
    p, c = frame.positions, frame.velocities
    return p[:, iu], p[:, iv], c[:, [iu, iv, ia]]


def _cic(grid: FieldGrid, u: np.ndarray, v: np.ndarray
         ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Cloud-in-cell: the four nodes of each particle (flat indices) and their weights,
    (4, N) each; particles beyond the grid go to its edge (none do inside the drum)."""
    n = grid.nodes
    fu = np.clip((u - grid.origin) / grid.spacing, 0.0, n - 1 - 1e-9)
    fv = np.clip((v - grid.origin) / grid.spacing, 0.0, n - 1 - 1e-9)
    iu, iv = np.floor(fu).astype(np.int64), np.floor(fv).astype(np.int64)
    tu, tv = fu - iu, fv - iv
    idx = np.stack([iv * n + iu, iv * n + iu + 1, (iv + 1) * n + iu, (iv + 1) * n + iu + 1])
    w = np.stack([(1 - tu) * (1 - tv), tu * (1 - tv), (1 - tu) * tv, tu * tv])
    return idx, w, fu, fv


def _smooth(grid: FieldGrid, sums: np.ndarray, kernel: np.ndarray) -> np.ndarray:
    """Node sums (..., nodes, nodes) convolved with the Gaussian, per unit volume."""
    out = ndimage.convolve1d(sums, kernel * grid.spacing, axis=-1, mode="constant")
    out = ndimage.convolve1d(out, kernel * grid.spacing, axis=-2, mode="constant")
    return out / (grid.spacing**2 * grid.length)


def _deposit(grid: FieldGrid, idx: np.ndarray, w: np.ndarray, values: np.ndarray) -> np.ndarray:
    """(K, nodes, nodes) node sums of K per-particle quantities ``values`` (K, N)."""
    n2 = grid.nodes * grid.nodes
    flat_idx = idx.ravel()
    return np.stack([np.bincount(flat_idx, weights=(w * q[None, :]).ravel(), minlength=n2)
                     for q in values]).reshape(len(values), grid.nodes, grid.nodes)


def flux_moments(frame: ParticleFrame, geo: DrumGeometry, grid: FieldGrid) -> np.ndarray:
    """(4, nodes, nodes): phi, phi u, phi v, phi c_axial of one frame (first pass)."""
    u, v, c = _in_plane(frame, geo.axis)
    vol = frame.volumes
    idx, w, _, _ = _cic(grid, u, v)
    sums = _deposit(grid, idx, w, np.vstack([vol, vol * c[:, 0], vol * c[:, 1], vol * c[:, 2]]))
    return _smooth(grid, sums, kernel_weights(grid))


def mean_velocity(flux: np.ndarray) -> np.ndarray:
    """(3, nodes, nodes) velocity (u, v, axial) of time-averaged flux moments (4, ...);
    0 where there is no material (those nodes carry no weight anywhere)."""
    phi = flux[0]
    with np.errstate(invalid="ignore", divide="ignore"):
        vel = np.where(phi > 0, flux[1:4] / np.where(phi > 0, phi, 1.0), 0.0)
    return vel


def fluctuation_moment(frame: ParticleFrame, geo: DrumGeometry, grid: FieldGrid,
                       velocity: np.ndarray) -> np.ndarray:
    """(nodes, nodes): sum V |c - u(x_i)|^2 K / L of one frame about the mean field
    ``velocity`` (3, nodes, nodes), interpolated bilinearly at each particle."""
    u, v, c = _in_plane(frame, geo.axis)
    idx, w, _, _ = _cic(grid, u, v)
    local = np.stack([np.sum(w * comp.ravel()[idx], axis=0) for comp in velocity], axis=1)
    dev2 = np.sum((c - local) ** 2, axis=1)
    sums = _deposit(grid, idx, w, (frame.volumes * dev2)[None, :])
    return _smooth(grid, sums, kernel_weights(grid))[0]


def window_means(frames: list[ParticleFrame], geo: DrumGeometry, kernel: float, cg: float,
                 length: float) -> WindowMeans:
    """The window-mean in-plane kernel sums (phi, phi u, phi v) of a case's steady frames
    at ``kernel`` CG1 diameters: the whole window, its first and its second half (with one
    frame, the halves are that frame)."""
    grid = field_grid(geo, kernel_width(geo, cg, kernel), length)
    flux = np.stack([flux_moments(f, geo, grid)[:IN_PLANE] for f in frames])
    half = len(frames) // 2 if len(frames) >= 2 else 1
    second = flux[half:] if len(frames) >= 2 else flux
    return WindowMeans(kernel=float(kernel), grid=grid,
                       sums=np.stack([flux.mean(axis=0), flux[:half].mean(axis=0),
                                      second.mean(axis=0)]))


def case_fields(frames: list[ParticleFrame], geo: DrumGeometry, width: float, length: float,
                head: dict, kernels: tuple[float, ...] = CRITERION_KERNELS) -> CaseFields:
    """The fields of one case from its steady-window frames (two passes: the mean flux,
    then the fluctuation about the window's mean velocity), with the window means at each
    of ``kernels`` CG1 diameters. ``head``: the case's identity (case_id, cg, rule,
    replica, group)."""
    grid = field_grid(geo, width, length)
    flux = np.stack([flux_moments(f, geo, grid) for f in frames])          # (F, 4, n, n)
    velocity = mean_velocity(flux.mean(axis=0))
    fluct = np.stack([fluctuation_moment(f, geo, grid, velocity) for f in frames])
    moments = np.concatenate([flux, fluct[:, None]], axis=1)
    means = tuple(window_means(frames, geo, k, head["cg"], length)
                  for k in sorted(set(kernels)))
    return CaseFields(**head, grid=grid, steps=np.array([f.step for f in frames], np.int64),
                      moments=moments, omega=float(geo.omega), radius=float(geo.radius),
                      window_means=means)


def reference_moments(frame: ParticleFrame, geo: DrumGeometry, grid: FieldGrid,
                      velocity: np.ndarray | None = None) -> np.ndarray:
    """The flux moments (4, n, n) of one frame, or with ``velocity`` its fluctuation
    moment, by direct summation of the truncated Gaussian (no deposit): slow, obviously
    right, for comparing with the fast path on small frames."""
    u, v, c = _in_plane(frame, geo.axis)
    vol = frame.volumes
    nodes = grid.origin + grid.spacing * np.arange(grid.nodes)
    du = nodes[None, :] - u[:, None]                       # (N, n): node u - particle u
    dv = nodes[None, :] - v[:, None]
    cut = KERNEL_CUTOFF * grid.width
    g1 = lambda d: np.where(np.abs(d) <= cut, np.exp(-0.5 * (d / grid.width) ** 2), 0.0)
    gu, gv = g1(du), g1(dv)
    reach = np.arange(-math.floor(cut / grid.spacing), math.floor(cut / grid.spacing) + 1)
    norm = (np.exp(-0.5 * (reach * grid.spacing / grid.width) ** 2).sum() * grid.spacing) ** 2
    if velocity is None:
        q = np.vstack([vol, vol * c[:, 0], vol * c[:, 1], vol * c[:, 2]])
    else:
        nu = (u - grid.origin) / grid.spacing
        nv = (v - grid.origin) / grid.spacing
        local = np.stack([ndimage.map_coordinates(comp, [nv, nu], order=1, mode="nearest")
                          for comp in velocity], axis=1)
        q = (vol * np.sum((c - local) ** 2, axis=1))[None, :]
    out = np.einsum("kn,nj,ni->kji", q, gv, gu) / (norm * grid.length)
    return out if velocity is None else out[0]
