"""Granule definitions: which bonds hold particles together, and how the bond graph is cut.

A definition is the study's :class:`~ligwf.scene.settings.AnalysisSettings` itself (its
``granules`` method and the fields after it, read as they are: no copy), in three parts,
applied to one frame by :func:`identify_granules`:

1. **Bonds** -- a dumped pair whose capillary force F (the engine's own law) exceeds
   ``min_bridge_force`` (N), whose relative force f_rel = F / (2 pi R* gamma cos theta)
   exceeds ``min_relative_force`` (CG-neutral: dimensionless under every rule), and whose
   partners move within ``max_velocity_angle`` (deg) of each other, the velocities taken in
   one of three frames: ``lab`` (as dumped; the source study), ``drum`` (minus the drum's
   rigid rotation omega x r about its axis through the origin, as templates/drum.in.j2
   turns it) or ``flow`` (minus the mean velocity of the particles within ``flow_radius``
   mean particle diameters, periodic along the drum axis).
2. **Partition** -- ``components``: connected components of the bonds (the source study;
   in a dense wet bed one cluster spans the bed); ``communities`` (the default):
   communities maximising the constant Potts model at ``resolution``, edge weight
   w n^2 and node weight n^3 at CG level n, where w is the bridge's relative rupture work
   e_rel = W / (F_0 R*) (``weight: energy``, the default: the energy needed to pull the
   pair apart, which grows with the bridge volume) or its relative force f_rel
   (``community_weight: force``: the touching force of the capillary laws does not depend on the
   liquid volume, so the partition barely responds to the liquid content). A CG-n contact
   stands for ~n^2 primary contacts across the same interface and a CG-n node for n^3
   primaries, so the CPM balance gives the same granule volume at every n (measured CG2/CG1
   d50 = 0.98-1.02). Why CPM, rupture work and a resolution of 0.002 by default:
   docs/results/granule_definitions.md.
3. **Granules** -- connected components of the bonds inside one partition class (for
   connected communities these are the communities; Louvain can leave one disconnected,
   which then counts as several granules), unwrapped along
   the periodic axis, each flagged when it closes a cycle around it (*percolating*).

Every part has a slow obvious reference beside its fast path: numpy bond test vs compiled
kernel, brute-force neighbour means vs a k-d tree, compiled Louvain vs the same Louvain in
plain Python (the same partition; igraph's Leiden compared by CPM quality), networkx BFS vs
compiled union-find.
"""

from __future__ import annotations

from dataclasses import dataclass, replace

import numpy as np

from ligwf.analysis.granules.bridge_law import Liquid, relative_energy, relative_force
from ligwf.analysis.granules.communities import cpm_labels, cpm_labels_reference
from ligwf.analysis.frames.dumps import ContactFrame, ParticleFrame
from ligwf.analysis.granules.bonds import (BondCriterion, Identification, bonded_contacts,
                                     bonded_contacts_reference, components, identify)
from ligwf.scene.axis import Axis
from ligwf.scene.settings import AnalysisSettings

#: the factors the sensitivity table moves each threshold by
SENSITIVITY_FACTORS = (0.8, 1.25)


def bond_criterion(definition: AnalysisSettings) -> BondCriterion:
    """The force (N) and angle part of the bond test of a definition."""
    return BondCriterion(definition.min_bridge_force, definition.max_velocity_angle)


def describe(definition: AnalysisSettings) -> str:
    """The definition in words, with the thresholds it uses (figure and table labels)."""
    d = definition
    if d.granules == "held":
        return f"held, bridges through {d.hold_time:g} s"
    parts = [d.granules]
    if d.granules == "communities":
        parts.append(f"resolution {d.resolution:g} ({d.community_weight} weight)")
    if d.max_velocity_angle < 180.0:
        parts.append(f"angle {d.max_velocity_angle:g} deg ({d.velocity_frame})")
    if d.min_relative_force > 0:
        parts.append(f"f_rel > {d.min_relative_force:g}")
    if d.min_bridge_force > 0:
        parts.append(f"F > {d.min_bridge_force:g} N")
    return ", ".join(parts)


def variants(definition: AnalysisSettings) -> list[tuple[str, AnalysisSettings]]:
    """(label, settings): the definition as set (its label states the setting), then each
    threshold it USES moved by x0.8 and x1.25: the hold time of ``held``, the CPM
    resolution of ``communities``, and the velocity angle, relative and absolute bridge
    force where they are on. A definition with no threshold in use (components of every
    bridge) has no variant."""
    d = definition

    def moved(**update) -> AnalysisSettings:
        return d.model_copy(update=update)

    out = [(f"as set: {describe(d)}", d)]
    for fac in SENSITIVITY_FACTORS:
        if d.granules == "held":
            out.append((f"hold {d.hold_time * fac:.3g} s", moved(hold_time=d.hold_time * fac)))
            continue
        if d.granules == "communities":
            out.append((f"resolution x{fac:g}", moved(resolution=d.resolution * fac)))
        if d.max_velocity_angle < 180.0:
            a = min(180.0, d.max_velocity_angle * fac)
            out.append((f"angle {a:.3g} deg ({d.velocity_frame})", moved(max_velocity_angle=a)))
        if d.min_relative_force > 0:
            f = d.min_relative_force * fac
            out.append((f"f_rel > {f:.3g}", moved(min_relative_force=f)))
        if d.min_bridge_force > 0:
            f = d.min_bridge_force * fac
            out.append((f"F > {f:.3g} N", moved(min_bridge_force=f)))
    return out


@dataclass(frozen=True)
class Motion:
    """What the velocity frames need of a run: the drum's rotation and its periodic axis."""

    rotation_axis: Axis         # the drum axis through the origin
    omega: float | None         # rad/s, positive about +axis; None: unknown (drum frame refused)
    periodic_axis: Axis | None
    length: float               # m, periodic length along periodic_axis

    @property
    def periodic_column(self) -> int | None:
        """Column of the periodic axis in a position (None: none), for the array kernels."""
        return None if self.periodic_axis is None else self.periodic_axis.index


def drum_frame_velocities(particles: ParticleFrame, motion: Motion) -> np.ndarray:
    """v - omega x r, m/s: velocities relative to the drum's rigid rotation."""
    if motion.omega is None:
        raise ValueError("velocity_frame drum needs the drum's angular velocity")
    w = np.zeros(3)
    w[motion.rotation_axis.index] = motion.omega
    return particles.velocities - np.cross(w, particles.positions)


def flow_frame_velocities(particles: ParticleFrame, motion: Motion, radius_diameters: float,
                          implementation: str = "fast") -> np.ndarray:
    """v minus the mean velocity of every particle within ``radius_diameters`` mean
    diameters (itself included; periodic along the periodic axis), m/s. ``fast``: k-d
    tree pairs; ``reference``: every pair's minimum-image distance in numpy."""
    pos, v = particles.positions, particles.velocities
    n = len(pos)
    radius = radius_diameters * 2.0 * float(particles.radii.mean())
    periodic = motion.periodic_axis is not None and motion.length > 0
    if implementation == "reference":
        total, count = v.copy(), np.ones(n)
        for a in range(n):
            d = pos - pos[a]
            if periodic:
                ax = motion.periodic_column
                d[:, ax] -= motion.length * np.round(d[:, ax] / motion.length)
            near = np.einsum("ij,ij->i", d, d) <= radius * radius
            near[a] = False
            total[a] += v[near].sum(axis=0)
            count[a] += near.sum()
        return v - total / count[:, None]
    from scipy.spatial import cKDTree

    lo = pos.min(axis=0)
    pts = pos - lo
    box = pts.max(axis=0) + 2.0 * radius + 1.0       # non-periodic sides never wrap
    if periodic:
        ax = motion.periodic_column
        pts[:, ax] = np.mod(pos[:, ax], motion.length)
        box[ax] = motion.length
    pairs = cKDTree(pts, boxsize=box).query_pairs(radius, output_type="ndarray")
    a, b = pairs[:, 0], pairs[:, 1]
    count = 1.0 + np.bincount(a, minlength=n) + np.bincount(b, minlength=n)
    total = v.copy()
    for d in range(3):
        total[:, d] += (np.bincount(a, weights=v[b, d], minlength=n)
                        + np.bincount(b, weights=v[a, d], minlength=n))
    return v - total / count[:, None]


def frame_velocities(particles: ParticleFrame, definition: AnalysisSettings, motion: Motion,
                     implementation: str = "fast") -> np.ndarray:
    """The velocities the angle test compares (m/s), in the definition's frame."""
    if definition.velocity_frame == "drum":
        return drum_frame_velocities(particles, motion)
    if definition.velocity_frame == "flow":
        return flow_frame_velocities(particles, motion, definition.flow_radius, implementation)
    return particles.velocities


def identify_granules(particles: ParticleFrame, contacts: ContactFrame, liquid: Liquid,
                      definition: AnalysisSettings, cg: float, motion: Motion,
                      implementation: str = "fast") -> Identification:
    """Granules of one frame under ``definition`` (``fast`` or ``reference``: the same
    granules; for communities the same CPM quality, see :mod:`ligwf.analysis.granules.communities`).
    ``cg``: the case's CG level n (CPM weights)."""
    if implementation not in ("fast", "reference"):
        raise ValueError(f"implementation {implementation!r}: use fast or reference")
    if definition.granules == "held":
        raise ValueError("granules: held needs the frames of its hold window "
                         "(ligwf.analysis.granules.persistent), not one frame")
    crit = bond_criterion(definition)
    if definition.max_velocity_angle < 180.0 and definition.velocity_frame != "lab":
        particles = replace(particles, velocities=frame_velocities(
            particles, definition, motion, implementation))
    axis, length = motion.periodic_column, motion.length
    if definition.granules == "components" and definition.min_relative_force == 0.0:
        return identify(particles, contacts, liquid, crit, axis, length, implementation)
    bonds = bonded_contacts if implementation == "fast" else bonded_contacts_reference
    i, j, force, rows = bonds(particles, contacts, liquid, crit, with_rows=True)
    f_rel = relative_force(force, particles.radii[i], particles.radii[j], liquid)
    keep = f_rel > definition.min_relative_force
    i, j, force, f_rel, rows = i[keep], j[keep], force[keep], f_rel[keep], rows[keep]
    if definition.granules == "communities":
        n = len(particles)
        weight = f_rel if definition.community_weight == "force" else relative_energy(
            particles, i, j, -contacts.delta[rows], liquid, implementation)
        partition = cpm_labels if implementation == "fast" else cpm_labels_reference
        community = partition(n, i, j, weight * cg ** 2, np.full(n, float(cg) ** 3),
                              definition.resolution, definition.community_seed)
        inside = community[i] == community[j]
        i, j, force = i[inside], j[inside], force[inside]
    return components(particles.positions, i, j, force, axis, length, implementation)


def cpm_weights(particles: ParticleFrame, contacts: ContactFrame, liquid: Liquid, cg: float,
                weight: str = "energy") -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """(i, j, edge weights w n^2, node weights n^3) of every bridge of a frame: the CPM
    graph of the default definition (``weight``: energy or force), for tests and
    benchmarks."""
    i, j, force, rows = bonded_contacts(particles, contacts, liquid,
                                        BondCriterion(0.0, 180.0), with_rows=True)
    if weight == "force":
        w = relative_force(force, particles.radii[i], particles.radii[j], liquid)
    else:
        w = relative_energy(particles, i, j, -contacts.delta[rows], liquid)
    return i, j, w * cg ** 2, np.full(len(particles), float(cg) ** 3)

