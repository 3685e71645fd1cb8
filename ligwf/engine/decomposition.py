"""Domain decomposition of a drum: the processor grid a case runs on and what it costs.

Pure functions, no I/O. LIGGGHTS cuts the box into a uniform ``Px x Py x Pz`` grid
(``processors``); the 3.8.0 engine has no load balancing to move the cuts (``balance`` is
``ERROR: Unknown command`` and ``fix balance`` ``Invalid fix style`` in the Debian 3.8.0
build, and the source tree has no balance.cpp; see docs/results/performance/scaling_model.md).
So the cuts stay where the uniform grid puts them, and the planner chooses the grid knowing
where the bed lies:

* **Along the axis** (periodic slice): the bed is uniform, every slab carries the same
  share; each slab at least :data:`MIN_AXIAL_SLAB` largest diameters long.
* **Across the drum** (horizontal, perpendicular to the axis): the bed is a circular segment
  whose free surface is tilted at the dynamic angle of repose, so uniform columns carry
  unequal shares (two columns split a turning bed 82/18 %, measured: 1.4x slower than two
  axial slabs). :func:`column_shares` gives each column's share of that segment; the slowest
  rank sets the pace, so the grid costs ``imbalance = columns x largest share``.
* **Never along gravity** (a settled bed is 96 % in the lower of two halves).

Every subdomain face inside the bed carries a halo of ghosts :data:`HALO_DIAMETERS` largest
diameters deep (measured: ``Nghost`` per rank at 1-8 ranks); a ghost costs
:data:`GHOST_COST` of an owned particle (calibrated so that two axial ranks of the 18 mm CG1
case keep 0.88 of the ideal, the project's one parallel measurement). Together:

    time per step of a grid ~ max over ranks of (owned + GHOST_COST x ghosts)

and the efficiency of a grid is that of one rank (its periodic images included) over ranks
x that. :func:`best_grid` gives the grid of a rank count (slabs first); the rank planner picks
the rank count whose grid gives the shortest run.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from functools import lru_cache

import numpy as np

from ligwf.errors import ConfigError
from ligwf.scene.scaled import ScaledScene

#: thinnest slab (along the axis) or column (across) one rank gets, in largest diameters
MIN_AXIAL_SLAB = 4.0
#: halo depth in largest diameters: ghosts per rank / (particle number density x face
#: area inside the bed), measured on the demo CG1 at 1-8 ranks (scaling_model.md)
HALO_DIAMETERS = 1.25
#: cost of one ghost relative to one owned particle per step (newton off: a pair across a
#: face is computed on both ranks; plus the exchange): two axial ranks of 11,963 CG1
#: particles in 18 mm at 0.88 of the ideal give 1.14
GHOST_COST = 1.14
#: dynamic angle of repose the bed's free surface is planned at (deg): the demo's wet CG1
#: flows at 46 deg, its cohesionless twin at 32, the We-vs-Bo drum at ~36
PLANNING_SURFACE_DEG = 40.0
#: across-cut half width of the box in drum radii (render.template_context: 1.05 R + d_max)
BOX_HALF_WIDTH = 1.05


def axial_slab_limit(drum_length: float, d_max: float) -> int:
    """Most ranks along the drum axis (m, m) that leave every slab at least MIN_AXIAL_SLAB
    largest diameters long; at least 1. (A length of exactly k slabs counts as k: the
    division is not left to round 2.9999 down.)"""
    return max(1, math.floor(drum_length / (MIN_AXIAL_SLAB * d_max) * (1.0 + 1e-9)))


@dataclass(frozen=True)
class Bed:
    """The cross-section the planner decomposes: drum diameter (m), the share of the drum
    the bed fills (0-1), its largest particle diameter (m), its surface angle (deg)."""

    drum_diameter: float
    fill_fraction: float
    d_max: float
    surface_deg: float = PLANNING_SURFACE_DEG

    def __post_init__(self) -> None:
        checks = (("drum_diameter", self.drum_diameter, 0.0, math.inf, "m"),
                  ("fill_fraction", self.fill_fraction, 0.0, 1.0, ""),
                  ("d_max", self.d_max, 0.0, math.inf, "m"),
                  ("surface_deg", self.surface_deg, -1.0, 90.0, "deg"))
        for name, value, lo, hi, unit in checks:
            if not isinstance(value, (int, float)) or not lo < value < hi:
                raise ConfigError(f"bed {name} = {value!r}: allowed range ({lo:g}, {hi:g}) "
                                  f"{unit}".rstrip())

    @property
    def box_width(self) -> float:
        """Width of the simulation box across the drum (m), what the columns divide."""
        return 2.0 * (BOX_HALF_WIDTH * 0.5 * self.drum_diameter + self.d_max)

    @property
    def across_limit(self) -> int:
        """Most columns across the box that are each >= MIN_AXIAL_SLAB largest diameters."""
        return max(1, math.floor(self.box_width / (MIN_AXIAL_SLAB * self.d_max) * (1 + 1e-9)))


_SAMPLES = 4001


@lru_cache(maxsize=256)
def _profile(bed: Bed) -> tuple[np.ndarray, np.ndarray]:
    """Bed depth (vertical extent, m) against the across coordinate u (m): the part of the
    disc below a surface line tilted at ``surface_deg`` that holds ``fill_fraction`` of it."""
    r = 0.5 * bed.drum_diameter
    half = 0.5 * bed.box_width
    u = np.linspace(-half, half, _SAMPLES)
    inside = np.clip(r * r - u * u, 0.0, None) ** 0.5
    slope = math.tan(math.radians(bed.surface_deg))

    def depth(c: float) -> np.ndarray:
        return np.clip(np.minimum(inside, slope * u + c) + inside, 0.0, None)

    target = bed.fill_fraction * math.pi * r * r
    du = u[1] - u[0]
    lo, hi = -r * (1 + slope) - r, r * (1 + slope) + r
    for _ in range(80):                     # bisection on the surface's intercept
        mid = 0.5 * (lo + hi)
        if depth(mid).sum() * du < target:
            lo = mid
        else:
            hi = mid
    return u, depth(0.5 * (lo + hi))


def column_shares(bed: Bed, columns: int) -> tuple[float, ...]:
    """Share of the bed's particles in each of ``columns`` equal columns across the box
    (sums to 1): what a uniform ``processors`` cut across the drum gives each rank."""
    _positive("columns", columns)
    u, d = _profile(bed)
    edges = np.linspace(u[0], u[-1], columns + 1)
    which = np.clip(np.searchsorted(edges, u, side="right") - 1, 0, columns - 1)
    sums = np.bincount(which, weights=d, minlength=columns)
    return tuple(float(s) for s in sums / sums.sum())


def _cut_depths(bed: Bed, columns: int) -> np.ndarray:
    """Bed depth (m) at each of the ``columns - 1`` inner cuts across the box."""
    u, d = _profile(bed)
    cuts = np.linspace(u[0], u[-1], columns + 1)[1:-1]
    return np.interp(cuts, u, d)


def _positive(field: str, value: object) -> int:
    if isinstance(value, bool) or not isinstance(value, int) or value < 1:
        raise ConfigError(f"{field} = {value!r}: must be a whole number (allowed range [1, inf))")
    return value


@dataclass(frozen=True)
class GridCost:
    """A processor grid of a case and its modelled cost relative to one rank."""

    axial: int                  # ranks along the axis
    across: int                 # ranks across the drum (horizontal)
    imbalance: float            # largest rank's particles / average (1: even)
    ghost_ratio: float          # ghosts / owned particles of the largest rank
    ghost_ratio_one: float      # the same on one rank (periodic images)
    efficiency: float           # speed-up / ranks, in (0, 1]

    @property
    def ranks(self) -> int:
        return self.axial * self.across

    def describe(self) -> str:
        """One line: the grid and what its efficiency rests on."""
        return (f"{self.axial} along the axis x {self.across} across: largest rank "
                f"{self.imbalance:.2f}x the average, halo {self.ghost_ratio:.2f} ghosts per "
                f"particle (1 rank: {self.ghost_ratio_one:.2f}), efficiency "
                f"{self.efficiency:.2f}")


def grid_cost(drum_length: float, d_max: float, periodic: bool, bed: Bed | None,
              axial: int, across: int) -> GridCost:
    """Modelled cost of ``axial x across`` ranks (module docstring). ``bed`` None: a case
    whose cross-section is unknown, cut along the axis only (``across`` must be 1)."""
    _positive("axial ranks", axial)
    _positive("across ranks", across)
    if bed is None and across > 1:
        raise ConfigError(f"across ranks = {across}: a cut across the drum needs its bed "
                          "(drum diameter and fill fraction)")
    return _grid_cost(drum_length, periodic, bed, axial, across, d_max)


def _grid_cost(length: float, periodic: bool, bed: Bed | None, axial: int, across: int,
               d_max: float) -> GridCost:
    halo = HALO_DIAMETERS * d_max
    slab = length / axial
    # axial faces: two per slab when the slice is periodic or cut, as depth per length
    faces_axial = 2 if (periodic or axial > 1) else 0
    one = (2 * halo / length) if periodic else 0.0
    g_axial = faces_axial * halo / slab if axial > 1 or periodic else 0.0
    if across == 1 or bed is None:
        imbalance, g_across = 1.0, 0.0
    else:
        shares = np.asarray(column_shares(bed, across))
        k = int(np.argmax(shares))
        cuts = _cut_depths(bed, across)
        faces = (cuts[k - 1] if k > 0 else 0.0) + (cuts[k] if k < across - 1 else 0.0)
        u, d = _profile(bed)
        area = float(d.sum() * (u[1] - u[0]))
        imbalance = float(across * shares[k])
        g_across = halo * faces / (shares[k] * area)
    ghost = g_axial + g_across
    efficiency = (1 + GHOST_COST * one) / (imbalance * (1 + GHOST_COST * ghost))
    return GridCost(axial, across, float(imbalance), float(ghost), float(one),
                    float(min(1.0, efficiency)))


def best_grid(ranks: int, drum_length: float, d_max: float, periodic: bool = True,
              bed: Bed | None = None) -> GridCost:
    """The ``axial x across = ranks`` grid with the most slabs along the axis (where the
    bed is even: measured) that keeps slabs and columns at least MIN_AXIAL_SLAB largest
    diameters, and its modelled cost (NaN without a ``bed``: the cut across is not costed).
    A rank count no such grid fits is refused (ConfigError). The rank planner chooses the
    rank count whose grid is fastest (:func:`ligwf.engine.plan.across_ranks`)."""
    _positive("ranks", ranks)
    max_axial = axial_slab_limit(drum_length, d_max)
    max_across = bed.across_limit if bed is not None else ranks
    options = [(a, ranks // a) for a in range(1, ranks + 1)
               if ranks % a == 0 and a <= max_axial and ranks // a <= max_across]
    if not options:
        raise ConfigError(f"ranks = {ranks}: no processor grid keeps slabs of >= "
                          f"{MIN_AXIAL_SLAB:g} largest diameters (at most {max_axial} along "
                          f"the axis x {max_across} across)")
    if bed is None:                 # no cross-section known: most ranks along the axis
        a, c = max(options)
        if c > 1:                   # the rest across, cost unknown (today's runner did so)
            return GridCost(a, c, math.nan, math.nan, math.nan, math.nan)
        return _grid_cost(drum_length, periodic, None, a, 1, d_max)
    a, c = max(options)             # axial first (measured even), the rest across
    return _grid_cost(drum_length, periodic, bed, a, c, d_max)


def scene_bed(scaled: ScaledScene) -> Bed:
    """The cross-section of a scaled case the decomposition plans with."""
    return Bed(scaled.drum.diameter, scaled.drum.fill_fraction, scaled.d_max)


def runner_grid(scaled: ScaledScene, ranks: int) -> tuple[int, int]:
    """(along the axis, across) ranks the runner gives a case on ``ranks`` ranks: the
    planner's :func:`best_grid`; a rank count no such grid fits (``--np`` by hand) keeps
    the slabs and puts the rest across, as before the 2-D planner."""
    try:
        grid = best_grid(ranks, scaled.drum.length, scaled.d_max, scaled.drum.periodic,
                         scene_bed(scaled))
    except ConfigError:
        grid = best_grid(ranks, scaled.drum.length, scaled.d_max, scaled.drum.periodic, None)
    return grid.axial, grid.across
