"""Where placed liquid goes: the wet spheres of ``liquid.placement: granules`` (pure).

The settled bed of fill fraction f fills a circular segment of the cross-section: its
chord lies at depth c = R cos(phi / 2) below the drum axis, phi - sin(phi) = 2 pi f. The
wet spheres are spread across the chord (at 0.6 of its half-width, equal steps), each
half-way between the free surface and the lifter tips below it, in the middle of the slice
along the axis. Coordinates are the drum frame's (axial, across, vertical) of
:attr:`ligwf.scene.axis.Axis.frame`: the renderer maps them onto x, y, z.
"""

from __future__ import annotations

import math

from ligwf.errors import ConfigError


def segment_angle(fill: float) -> float:
    """Central angle phi (rad) of the circular segment holding ``fill`` of the circle."""
    lo, hi = 0.0, 2.0 * math.pi
    for _ in range(200):                       # phi - sin(phi) is monotonic on [0, 2 pi]
        mid = 0.5 * (lo + hi)
        if mid - math.sin(mid) < 2.0 * math.pi * fill:
            lo = mid
        else:
            hi = mid
    return 0.5 * (lo + hi)


def wet_sphere_centres(radius: float, inner_radius: float, length: float, fill: float,
                       count: int, sphere_radius: float) -> tuple[tuple[float, float, float], ...]:
    """(axial, across, vertical) centres, m, of ``count`` wet spheres of ``sphere_radius``
    in the settled bed of a drum of ``radius`` (``inner_radius``: at the lifter tips)."""
    phi = segment_angle(fill)
    depth = radius * math.cos(0.5 * phi)                 # chord below the axis, m (< 0: above)
    half = 0.6 * radius * math.sin(0.5 * phi)
    out = []
    for k in range(count):
        u = -half + 2.0 * half * (k + 0.5) / count
        floor = -math.sqrt(max(inner_radius ** 2 - u * u, 0.0))
        v = 0.5 * (-depth + floor)
        if (-depth) - v < sphere_radius or v - floor < sphere_radius:
            raise ConfigError(
                f"scene.liquid.wet_granules.radius = {sphere_radius:g} m: a wet sphere does not "
                f"fit in the settled bed ({(-depth - floor) / 2:.3g} m from its surface to the "
                "lifter tips at its place); use a smaller radius or a larger fill_fraction")
        out.append((0.5 * length, u, v))
    return tuple(out)


def wet_sphere_fields(scene, largest_diameter: float, cg: float) -> dict:
    """The :class:`~ligwf.scene.scaled.ScaledLiquidValues` fields of placed liquid (none for a
    uniformly wetted bed): the wet spheres (axial, across, vertical, radius) and their
    liquid content. A sphere smaller than the largest (CG-scaled) particle diameter is
    refused: it would hold no or a single particle centre, a dry bed in all but name."""
    g = scene.liquid.wet_granules
    if scene.liquid.placement != "granules" or g is None:
        return {}
    if g.radius < largest_diameter:
        raise ConfigError(
            f"scene.liquid.wet_granules.radius = {g.radius:g} m: below the largest particle "
            f"diameter at CG{cg:g} ({largest_diameter:.3g} m), so a wet sphere holds no "
            f"particle; allowed range [{largest_diameter:.3g}, 1] m at this CG level")
    drum = scene.drum
    inner = drum.radius - (drum.lifters.height if drum.lifters.count else 0.0)
    centres = wet_sphere_centres(drum.radius, inner, drum.length, scene.process.fill_fraction,
                                 g.count, g.radius)
    return {"wet_spheres": tuple((*c, g.radius) for c in centres),
            "wet_sphere_content": g.liquid_content}
