"""The drum's geometry counted in grains of each CG level: what a CG-n bed can still
resolve.

At a fixed drum a CG-n grain is n times larger, so the lifters, the periodic slice, the
bed's depth and its flowing layer hold n times fewer grains across: the source study's
1 mm lifters are below one grain at every level above CG1, and a flowing layer of 9 mm holds
9 CG1 grains but 3 at CG3. ``ligwf check`` prints these counts per level before a run and
warns where a lifter is lower than one grain (it then acts as wall roughness, not as a
lifter); the report adds the measured flowing layer in grains.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

from scipy import optimize

from ligwf.scene.model import Scene
from ligwf.scene.scaled import ScaledScene


@dataclass(frozen=True)
class Grains:
    """Lengths of a scene in grains of CG level ``cg`` (the CG1 mean diameter times cg)."""

    cg: float
    diameter: float       # m, the CG-n mean diameter
    lifter: float         # lifter height / diameter (0: no lifters)
    slice: float          # periodic slice (drum length) / diameter
    bed_depth: float      # bed depth at rest (fill fraction's circular segment) / diameter

    @property
    def warning(self) -> str | None:
        """One line when a lifter is lower than one grain."""
        if 0 < self.lifter < 1.0:
            return (f"CG{self.cg:g}: the lifters are {self.lifter:.2g} grains high "
                    f"(lower than one CG{self.cg:g} diameter of {self.diameter * 1e3:.3g} mm): "
                    "they act as wall roughness, not as lifters, at this level")
        return None


def mean_diameter(scene: Scene) -> float:
    """The number-weighted mean CG1 diameter of a scene (m)."""
    sizes = scene.particles.size_distribution
    return sum(s.diameter * s.fraction for s in sizes) / sum(s.fraction for s in sizes)


def segment_depth(radius: float, fill: float) -> float:
    """Depth (m) of the circular segment holding ``fill`` of the drum's cross-section: the
    depth of a bed at rest."""
    if not 0 < fill < 1:
        return math.nan

    def area(h: float) -> float:   # segment of depth h over the circle's area
        a = math.acos(1.0 - h / radius)
        return (a - math.sin(a) * math.cos(a)) / math.pi - fill

    return float(optimize.brentq(area, 0.0, 2.0 * radius))


def grains(scene: Scene, cg: float) -> Grains:
    """The scene's lengths in grains of CG level ``cg``."""
    d = cg * mean_diameter(scene)
    drum = scene.drum
    lifter = drum.lifters.height / d if drum.lifters.count else 0.0
    depth = segment_depth(0.5 * drum.diameter, scene.process.fill_fraction)
    return Grains(cg, d, lifter, drum.length / d, depth / d)


def scaled_mean_diameter(scaled: ScaledScene) -> float:
    """The number-weighted mean particle diameter of a scaled (CG-n) scene (m)."""
    d, f = scaled.particles.diameters, scaled.particles.number_fractions
    return float(sum(a * b for a, b in zip(d, f)))


def study_strip(mean_diameters, setting: float | None = None) -> float | None:
    """The strip width of a study's angle of repose (m): ``setting`` when given (0: None,
    each case at twice its own diameter, the rule before the width was fixed), else twice
    the largest mean particle diameter among its cases (its coarsest CG level), the same
    physical resolution at every level so that a difference CG-n - CG1 carries no
    difference of resolution (:mod:`ligwf.analysis.flow.surface`). Twice, as before at
    each level: on the real CG3 bed of tests/data (222 beads, a slice 4 diameters long)
    strips one diameter wide moved the angle from 45.9 to 36.2 deg, too few grains per
    strip for the walk down from its top. A bed too small for 4 strips of that width at the
    coarsest level then has no angle at any level: the same resolution or none."""
    if setting is not None:
        return float(setting) if setting > 0 else None
    d = [float(x) for x in mean_diameters if x and math.isfinite(float(x))]
    return 2.0 * max(d) if d else None


#: the share of the half chord the surface fit uses (ligwf.analysis.flow.surface.SPAN) and
#: the fewest strips it fits a line through
SURFACE_SPAN, SURFACE_MIN_STRIPS = 0.7, 4


def surface_strips(scene: Scene, strip: float) -> int:
    """How many full strips of width ``strip`` (m) the surface fit can cut from the chord
    of the bed at rest: with fewer than SURFACE_MIN_STRIPS no angle of repose is measured
    (at any level, when ``strip`` is the study's one resolution)."""
    radius = 0.5 * scene.drum.diameter
    depth = segment_depth(radius, scene.process.fill_fraction)
    half = SURFACE_SPAN * math.sqrt(max(radius ** 2 - (radius - depth) ** 2, 0.0))
    k = math.floor(half / strip)
    return 2 * k + (2 if half - k * strip >= 0.5 * strip else 0)


def strip_warning(scene: Scene, strip: float | None) -> str | None:
    """One line when the study's strips leave the fit fewer than its fewest strips."""
    if not strip:
        return None
    n = surface_strips(scene, strip)
    if n >= SURFACE_MIN_STRIPS:
        return None
    return (f"analysis.surface_strip: the study's one resolution, strips of "
            f"{strip * 1e3:.3g} mm, cuts the bed's surface into "
            f"{n} strips, fewer than the {SURFACE_MIN_STRIPS} the fit needs: no angle of "
            "repose at any level; lower the coarsest CG level or set analysis.surface_strip "
            "(0: each case's own 2 d, whose resolution moves with the level)")
