"""Granule definitions: which bonds hold particles together, and how the bond graph is cut.

A definition (:class:`GranuleDefinition`, built from the study's ``analysis:`` block) has
three parts, applied to one frame by :func:`identify_granules`:

1. **Bonds** -- a dumped pair whose capillary force F (the engine's own law) exceeds
   ``min_bridge_force`` (N), whose relative force f_rel = F / (2 pi R* gamma cos theta)
   exceeds ``min_relative_force`` (CG-neutral: dimensionless under every rule), and whose
   partners move within ``max_velocity_angle_deg`` of each other, the velocities taken in
   one of three frames: ``lab`` (as dumped; the source study), ``drum`` (minus the drum's
   rigid rotation omega x r about its axis through the origin, as templates/drum.in.j2
   turns it) or ``flow`` (minus the mean velocity of the particles within ``flow_radius``
   mean particle diameters, periodic along the drum axis).
2. **Partition** -- ``components``: connected components of the bonds (the source study;
   in a dense wet bed one cluster spans the bed); ``communities`` (the default):
   communities maximising the constant Potts model with resolution gamma, edge weight
   w n^2 and node weight n^3 at CG level n, where w is the bridge's relative rupture work
   e_rel = W / (F_0 R*) (``weight: energy``, the default: the energy needed to pull the
   pair apart, which grows with the bridge volume) or its relative force f_rel
   (``weight: force``: the touching force of the capillary laws does not depend on the
   liquid volume, so the partition barely responds to the liquid content). A CG-n contact
   stands for ~n^2 primary contacts across the same interface and a CG-n node for n^3
   primaries, so the CPM balance gives the same granule volume at every n (measured CG2/CG1
   d50 = 0.98-1.02). Why CPM, rupture work and gamma = 0.002 by default:
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

from ligwf.analysis.bridge_law import Liquid, relative_energy, relative_force
from ligwf.analysis.communities import cpm_labels, cpm_labels_reference
from ligwf.analysis.dumps import ContactFrame, ParticleFrame
from ligwf.analysis.granules import (BondCriterion, Identification, bonded_contacts,
                                     bonded_contacts_reference, components, identify)

METHODS = ("communities", "components", "held")
#: CPM edge weights: the bridge's relative rupture work or its relative force
WEIGHTS = ("energy", "force")
VELOCITY_FRAMES = ("lab", "drum", "flow")
#: the factors the sensitivity table moves each threshold by
SENSITIVITY_FACTORS = (0.8, 1.25)


@dataclass(frozen=True)
class GranuleDefinition:
    """A full granule definition (see the module docstring); defaults: the measured one."""

    method: str = "communities"
    velocity_frame: str = "lab"
    max_velocity_angle_deg: float = 180.0
    min_bridge_force: float = 0.0          # N
    min_relative_force: float = 0.0        # F / (2 pi R* gamma cos theta)
    resolution: float = 0.002              # CPM gamma
    seed: int = 0                          # seed of the CPM node order
    flow_radius: float = 3.0               # mean particle diameters
    weight: str = "energy"                 # CPM edge weight: energy (e_rel) | force (f_rel)
    hold_time: float = 0.5                 # s, method held: bridges present through [t, t + this]

    def __post_init__(self) -> None:
        if self.method not in METHODS:
            raise ValueError(f"method {self.method!r}: use one of {METHODS}")
        if self.velocity_frame not in VELOCITY_FRAMES:
            raise ValueError(f"velocity_frame {self.velocity_frame!r}: use one of {VELOCITY_FRAMES}")
        if self.weight not in WEIGHTS:
            raise ValueError(f"weight {self.weight!r}: use one of {WEIGHTS}")
        if not self.hold_time > 0:
            raise ValueError(f"hold_time {self.hold_time!r}: must be > 0 s")
        if not (self.resolution > 0 and self.flow_radius > 0 and self.min_relative_force >= 0):
            raise ValueError(f"{self}: resolution and flow_radius must be > 0, "
                             "min_relative_force >= 0")

    @classmethod
    def of_settings(cls, s) -> "GranuleDefinition":
        """The definition of a study's :class:`~ligwf.scene.settings.AnalysisSettings`."""
        return cls(s.granules, s.velocity_frame, float(s.max_velocity_angle),
                   float(s.min_bridge_force), float(s.min_relative_force),
                   float(s.resolution), int(s.community_seed), float(s.flow_radius),
                   s.community_weight, float(getattr(s, "hold_time", 0.5)))

    @property
    def criterion(self) -> BondCriterion:
        """The force (N) and angle part of the bond test."""
        return BondCriterion(self.min_bridge_force, self.max_velocity_angle_deg)

    def setting(self) -> str:
        """The definition in words, with the thresholds it uses (figure and table labels)."""
        if self.method == "held":
            return f"held, bridges through {self.hold_time:g} s"
        parts = [self.method]
        if self.method == "communities":
            parts.append(f"resolution {self.resolution:g} ({self.weight} weight)")
        if self.max_velocity_angle_deg < 180.0:
            parts.append(f"angle {self.max_velocity_angle_deg:g} deg ({self.velocity_frame})")
        if self.min_relative_force > 0:
            parts.append(f"f_rel > {self.min_relative_force:g}")
        if self.min_bridge_force > 0:
            parts.append(f"F > {self.min_bridge_force:g} N")
        return ", ".join(parts)

    def variants(self) -> list[tuple[str, "GranuleDefinition"]]:
        """(label, definition): the definition as set (its label states the setting), then
        each threshold it USES moved by x0.8 and x1.25: the hold time of ``held``, the CPM
        resolution of ``communities``, and the velocity angle, relative and absolute
        bridge force where they are on. A definition with no threshold in use (components
        of every bridge) has no variant."""
        out = [(f"as set: {self.setting()}", self)]
        for fac in SENSITIVITY_FACTORS:
            if self.method == "held":
                out.append((f"hold {self.hold_time * fac:.3g} s",
                             replace(self, hold_time=self.hold_time * fac)))
                continue
            if self.method == "communities":
                out.append((f"resolution x{fac:g}", replace(self, resolution=self.resolution * fac)))
            if self.max_velocity_angle_deg < 180.0:
                a = min(180.0, self.max_velocity_angle_deg * fac)
                out.append((f"angle {a:.3g} deg ({self.velocity_frame})",
                            replace(self, max_velocity_angle_deg=a)))
            if self.min_relative_force > 0:
                f = self.min_relative_force * fac
                out.append((f"f_rel > {f:.3g}", replace(self, min_relative_force=f)))
            if self.min_bridge_force > 0:
                f = self.min_bridge_force * fac
                out.append((f"F > {f:.3g} N", replace(self, min_bridge_force=f)))
        return out


@dataclass(frozen=True)
class Motion:
    """What the velocity frames need of a run: the drum's rotation and its periodic axis."""

    rotation_axis: int          # 0, 1, 2: the drum axis (x, y, z) through the origin
    omega: float | None         # rad/s, positive about +axis; None: unknown (drum frame refused)
    periodic_axis: int | None
    length: float               # m, periodic length along periodic_axis


def drum_frame_velocities(particles: ParticleFrame, motion: Motion) -> np.ndarray:
    """v - omega x r, m/s: velocities relative to the drum's rigid rotation."""
    if motion.omega is None:
        raise ValueError("velocity_frame drum needs the drum's angular velocity")
    w = np.zeros(3)
    w[motion.rotation_axis] = motion.omega
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
                ax = motion.periodic_axis
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
        ax = motion.periodic_axis
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


def frame_velocities(particles: ParticleFrame, definition: GranuleDefinition, motion: Motion,
                     implementation: str = "fast") -> np.ndarray:
    """The velocities the angle test compares (m/s), in the definition's frame."""
    if definition.velocity_frame == "drum":
        return drum_frame_velocities(particles, motion)
    if definition.velocity_frame == "flow":
        return flow_frame_velocities(particles, motion, definition.flow_radius, implementation)
    return particles.velocities


def identify_granules(particles: ParticleFrame, contacts: ContactFrame, liquid: Liquid,
                      definition: GranuleDefinition, cg: float, motion: Motion,
                      implementation: str = "fast") -> Identification:
    """Granules of one frame under ``definition`` (``fast`` or ``reference``: the same
    granules; for communities the same CPM quality, see :mod:`ligwf.analysis.communities`).
    ``cg``: the case's CG level n (CPM weights)."""
    if implementation not in ("fast", "reference"):
        raise ValueError(f"implementation {implementation!r}: use fast or reference")
    if definition.method == "held":
        raise ValueError("granules: held needs the frames of its hold window "
                         "(ligwf.analysis.persistent), not one frame")
    crit = definition.criterion
    if definition.max_velocity_angle_deg < 180.0 and definition.velocity_frame != "lab":
        particles = replace(particles, velocities=frame_velocities(
            particles, definition, motion, implementation))
    axis, length = motion.periodic_axis, motion.length
    if definition.method == "components" and definition.min_relative_force == 0.0:
        return identify(particles, contacts, liquid, crit, axis, length, implementation)
    bonds = bonded_contacts if implementation == "fast" else bonded_contacts_reference
    i, j, force, rows = bonds(particles, contacts, liquid, crit, with_rows=True)
    f_rel = relative_force(force, particles.radii[i], particles.radii[j], liquid)
    keep = f_rel > definition.min_relative_force
    i, j, force, f_rel, rows = i[keep], j[keep], force[keep], f_rel[keep], rows[keep]
    if definition.method == "communities":
        n = len(particles)
        weight = f_rel if definition.weight == "force" else relative_energy(
            particles, i, j, -contacts.delta[rows], liquid, implementation)
        partition = cpm_labels if implementation == "fast" else cpm_labels_reference
        community = partition(n, i, j, weight * cg ** 2, np.full(n, float(cg) ** 3),
                              definition.resolution, definition.seed)
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

