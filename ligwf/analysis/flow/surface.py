"""Free surface of a rotating-drum bed: a robust straight-line fit in the cross-section.

Why not the highest particle per vertical strip: in a cascading wet bed a few particles are
airborne above the surface, lifters carry clumps up the rising wall, and a vertical strip
near the wall cuts the surface at a slant. A plain least-squares line through the strip
maxima then follows those outliers (ligwf 0.1 reported 39 deg where an independent fit gave
36 deg) and ``abs(slope)`` hid a surface tilted the wrong way.

The estimator (all lengths in m, angles in degrees):

1. First guess from the centre of mass: for a flat surface the bed is a circular segment
   whose centre of mass lies on the chord's perpendicular through the drum centre, so the
   surface tangent is tilted by the centre-of-mass angle from straight down.
2. Rotate into surface coordinates (x along the guessed tangent, y along its upward normal)
   and cut the central part of the chord (``span`` of the half chord, away from the walls
   and the lifters) into strips across the surface, on a grid anchored at the centre line.
   Their width is the measurement's resolution: one physical width for every CG level of
   a study (twice its coarsest level's diameter, :func:`ligwf.scene.grains.study_strip`), so
   CG1 and CG-n surfaces are sampled at the same places (with strips of 2 d, a CG3 bed gave 5 strips
   where CG1 gave 16, and the line through a curved surface moved by up to 1 deg with d
   alone: tests/analysis/flow/test_surface_resolution.py).
3. Surface point of a strip: walk down from its highest particle top (y + r) and take the
   first one whose next lower neighbour in the strip is less than one diameter below it
   (a particle separated from the bed by a gap is airborne, not surface).
4. Robust line fit: least median of squares over all point pairs (up to half the points
   may be outliers), then least squares on the points within 3 scaled median absolute
   deviations of it (at least a quarter of the strip width), until nothing changes.
5. Repeat 2-4 once about the refined tangent (strips then cut the surface square on);
   when that pass finds fewer than 4 strips, the first pass's line is the fit.

The angle is signed with respect to the rotation: positive when the surface rises towards
the wall that moves up (the ordinary dynamic angle of repose), negative for a surface
tilted the other way.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np

from ligwf.scene.grains import SURFACE_SPAN

SPAN = SURFACE_SPAN  # share of the half chord used for the fit (walls and lifters left out)
MAD_CUT = 3.0       # outliers: residual beyond this many scaled MADs
MAD_SCALE = 1.4826  # MAD -> standard deviation for normal scatter


@dataclass(frozen=True)
class SurfaceFit:
    """A fitted free surface in the drum cross-section (u horizontal, v up)."""

    tangent_deg: float   # angle of the surface tangent from +u, counter-clockwise in (u, v)
    angle_deg: float     # signed angle of repose (positive: rises towards the rising wall)
    offset: float        # m, signed distance of the surface line from the drum centre
    points: int          # strip points used in the final fit
    rejected: int        # strip points rejected as outliers


def _strip_tops(x: np.ndarray, top: np.ndarray, width: float, half: float,
                gap: float) -> tuple[np.ndarray, np.ndarray]:
    """(x centre, surface height) per strip over |x| < half; airborne particles skipped.
    The strips sit on a grid anchored at the bed's centre line (x = 0) and end at +-half
    (an end strip cut to under half a width is left out), so two beds of other particle sizes are cut at the same
    places when ``width`` is the same. (The former grid started at -half and its last strip
    ran up to a width past +half: the window itself grew with the strip width.)"""
    k = math.ceil(half / width)
    edges = np.unique(np.clip(np.arange(-k, k + 1) * width, -half, half))
    idx = np.where(np.abs(x) < half, np.digitize(x, edges) - 1, -1)
    xs, ys = [], []
    for k in range(len(edges) - 1):
        if edges[k + 1] - edges[k] < 0.5 * width:
            continue   # an end strip cut to under half a width: too few particles to trust
        h = np.sort(top[idx == k])[::-1]
        if len(h) < 3:
            continue
        drops = np.flatnonzero(h[:-1] - h[1:] < gap)
        if len(drops):
            xs.append(0.5 * (edges[k] + edges[k + 1]))
            ys.append(h[drops[0]])
    return np.asarray(xs), np.asarray(ys)


def robust_line(x: np.ndarray, y: np.ndarray, floor: float) -> tuple[float, float, np.ndarray]:
    """(slope, intercept, kept mask) of a robust line fit.

    Start: least median of squares over the lines through every pair of points (correct
    with up to half the points off the surface: airborne pairs, lifter clumps); then least
    squares on the points within ``MAD_CUT`` scaled MADs of the line (at least ``floor``,
    m), repeated until the kept set does not change.
    """
    i, j = np.triu_indices(len(x), 1)
    ok = x[j] != x[i]
    i, j = i[ok], j[ok]
    slopes = (y[j] - y[i]) / (x[j] - x[i])
    inter = y[i] - slopes * x[i]
    med = np.median((y[None, :] - (slopes[:, None] * x[None, :] + inter[:, None])) ** 2, axis=1)
    best = int(np.argmin(med))
    a, b = float(slopes[best]), float(inter[best])
    keep = np.ones(len(x), bool)
    for _ in range(10):
        res = y - (a * x + b)
        cut = max(MAD_CUT * MAD_SCALE * float(np.median(np.abs(res))), floor)
        new = np.abs(res) <= cut
        if new.sum() < 3:
            break
        a, b = (float(c) for c in np.polyfit(x[new], y[new], 1))
        if np.array_equal(new, keep):
            break
        keep = new
    return a, b, keep


def fit_surface(u: np.ndarray, v: np.ndarray, r: np.ndarray, radius: float, d: float,
                rising_side: float, span: float = SPAN, strip: float | None = None
                ) -> SurfaceFit | None:
    """Fit the free surface of a bed (see the module docstring); None when too few strips.

    ``u, v, r``: particle centres and radii in the cross-section (m); ``radius``: drum
    radius; ``d``: particle diameter (the gaps between particles of a strip, the fit's
    floor); ``strip``: the strips' width in m, the measurement's resolution (None: 2 d,
    the particle's own scale, which makes the resolution move with the CG level: a study
    passes one physical width for all its levels,
    :func:`ligwf.scene.grains.study_strip`); ``rising_side``:
    +1 when the wall at +u moves up, -1 when the wall at -u does.
    """
    if len(u) < 10:
        return None
    w = r**3  # one density: volume weights are mass weights
    cu, cv = float(np.average(u, weights=w)), float(np.average(v, weights=w))
    tangent = math.atan2(cu, -cv) if math.hypot(cu, cv) > 0.02 * radius else 0.0
    fit = None
    for _ in range(2):
        c, s = math.cos(tangent), math.sin(tangent)
        x, y = u * c + v * s, -u * s + v * c
        h = float(np.quantile(y + r, 0.98))
        half = span * math.sqrt(max(radius**2 - min(h * h, radius**2), 0.0))
        width = strip if strip else 2.0 * d
        xs, ys = _strip_tops(x, y + r, width, half, d)
        if len(xs) < 4:
            break   # the first pass's line stands when the second finds too few strips
        a, b, keep = robust_line(xs, ys, 0.25 * width)   # 0.5 d at the former 2 d strips
        tangent += math.atan(a)
        fit = (tangent, b * math.cos(math.atan(a)), int(keep.sum()), int((~keep).sum()))
    if fit is None:
        return None
    tangent, offset, used, rejected = fit
    deg = math.degrees(tangent)
    deg = (deg + 90.0) % 180.0 - 90.0
    return SurfaceFit(tangent_deg=deg, angle_deg=deg * (1.0 if rising_side >= 0 else -1.0),
                      offset=offset, points=used, rejected=rejected)

