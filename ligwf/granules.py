"""Granule identification: liquid-bonded contacts -> connected components -> granule table.

A contact of the contact dump is a *liquid bond* when (criteria after Dong et al., as used
by the source study):

1. its liquid-bridge (capillary, cohesive) force exceeds ``min_bridge_force`` (N), and
2. the angle between the two partners' velocity vectors is below ``max_velocity_angle_deg``.

The bridge force is evaluated from the geometry with the engine's own law
(:func:`ligwf.bridges.capillary_force`, verified against LIGGGHTS to 1e-9) from the
dumped overlap ``delta`` (gap = -delta), the radii and the liquid content of both
partners: the dumped total force cannot be used directly because for touching pairs it
includes the Hertz repulsion. Separated pairs (delta < 0) within the rupture distance
carry a bridge and count; beyond rupture the law gives 0 and the pair is not bonded.

Granules are the connected components of the bonded graph (built on particle ids, never on
geometry, since pairs across the periodic boundary span the box). Two implementations:
:func:`label_reference` (networkx BFS, the method of the source study: slow, obviously
right) and :func:`label_fast` (compiled union-find, :mod:`ligwf.granules_numba`); both
return the same canonical labels (granule 0 holds the particle with the smallest id, and so
on), which the tests check on real dumps and on random graphs. The bond test itself
(:func:`bonded_contacts`) is one compiled pass over the contacts; the numpy evaluation of
the same criterion, :func:`bonded_contacts_reference`, is kept as its reference.

Centres of mass are computed with positions unwrapped along the bonds across the
periodic axis (a granule straddling y = 0 / y = L has its centre inside it, not in the
middle of the box), then wrapped back into the box. All particles of a ligwf scene share
one density, so centres of mass are volume-weighted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from . import bridges
from .dumps import ContactFrame, ParticleFrame

AXES = "xyz"


@dataclass(frozen=True)
class BondCriterion:
    """When a contact is a liquid bond.

    ``min_bridge_force`` (N), default 0: every bridge the engine still holds (gap below
    the rupture distance) counts. A positive absolute threshold would not be CG-neutral:
    bridge forces grow like n (Weber rule) or n^2 (Bond rule) with the CG level, so one
    number in newtons cuts different shares of the bridges at each level and rule.

    ``max_velocity_angle_deg``, default 30 deg (Dong et al.'s co-moving criterion; the value
    of LIGGGHTS_NOTES' measurements): partners moving in directions more than 30 deg apart
    are being sheared or torn apart by the flow rather than moving as one body, so their
    bridge does not hold them in one granule. A partner at rest (zero speed) has no
    direction and is taken as co-moving.
    """

    min_bridge_force: float = 0.0
    max_velocity_angle_deg: float = 30.0

    def __post_init__(self) -> None:
        if not (self.min_bridge_force >= 0.0 and math.isfinite(self.min_bridge_force)):
            raise ValueError(f"min_bridge_force = {self.min_bridge_force}: must be >= 0 N")
        if not 0.0 <= self.max_velocity_angle_deg <= 180.0:
            raise ValueError(f"max_velocity_angle_deg = {self.max_velocity_angle_deg}: "
                             "allowed range [0, 180]")


@dataclass(frozen=True)
class Liquid:
    """The liquid-bridge law the engine applied in a run (from ``scene.json``'s scaled part)."""

    model: str                  # washino | easo | none
    surface_tension: float      # N/m, already CG-scaled
    contact_angle_rad: float    # the angle the engine APPLIED (see ligwf.bridges)
    liquid_content: float       # fraction of particle volume, used if a dump lacks it

    @classmethod
    def from_scaled(cls, scaled: dict, engine_product_bug: bool = True) -> "Liquid":
        """From ``ScaledScene.to_dict()``. ligwf writes a compensated input angle so the
        3.8.0 engine applies the scene angle; without compensation it applied 0.5 a^2."""
        theta_deg = float(scaled.get("contact_angle_deg", 0.0))
        if scaled.get("contact_angle_compensation", True) or not engine_product_bug:
            theta = math.radians(theta_deg)
        else:
            theta = bridges.engine_effective_angle_rad(theta_deg, product_bug=True)
        return cls(str(scaled.get("liquid_model", "none")), float(scaled.get("surface_tension", 0.0)),
                   theta, float(scaled.get("liquid_content", 0.0)))


def bridge_forces(particles: ParticleFrame, contacts: ContactFrame, liquid: Liquid,
                  i: np.ndarray | None = None, j: np.ndarray | None = None) -> np.ndarray:
    """Capillary force magnitude of every contact, N (0 for a dry run or a broken bridge)."""
    i = particles.index_of(contacts.id1) if i is None else i
    j = particles.index_of(contacts.id2) if j is None else j
    return _capillary(particles, i, j, -contacts.delta, liquid)


def _capillary(particles: ParticleFrame, i: np.ndarray, j: np.ndarray, gap: np.ndarray,
               liquid: Liquid) -> np.ndarray:
    if liquid.model == "none" or len(i) == 0:
        return np.zeros(len(i))
    content = particles.liquid_content
    if content is None:
        content = np.full(len(particles), liquid.liquid_content)
    return np.asarray(bridges.capillary_force(
        liquid.model, particles.radii[i], particles.radii[j], gap,
        liquid.surface_tension, liquid.contact_angle_rad, content[i], content[j]), dtype=float)


def comoving(v_i: np.ndarray, v_j: np.ndarray, max_angle_deg: float) -> np.ndarray:
    """True where the angle between v_i and v_j (rows, m/s) is <= max_angle_deg.

    Compared as cos(angle) >= cos(max) without arccos; a zero velocity counts as co-moving.
    """
    dot = np.einsum("ij,ij->i", v_i, v_j)
    norms = np.sqrt(np.einsum("ij,ij->i", v_i, v_i) * np.einsum("ij,ij->i", v_j, v_j))
    return (norms == 0.0) | (dot >= math.cos(math.radians(max_angle_deg)) * norms)


def bonded_contacts(particles: ParticleFrame, contacts: ContactFrame, liquid: Liquid,
                    criterion: BondCriterion = BondCriterion()):
    """Indices (i, j) of bonded pairs into the particle arrays, and their bridge forces (N).

    One compiled pass over the contacts (:func:`ligwf.granules_numba.bond_kernel`): the
    rupture distance and velocity-angle tests, then the force law of the liquid model only
    for the pairs that pass both; pairs in contact order. The same pairs as
    :func:`bonded_contacts_reference`, forces equal to rounding (~1e-16 relative), tested
    on real dumps and random frames.
    """
    from .granules_numba import MODEL_CODES, bond_kernel

    if liquid.model not in MODEL_CODES:
        raise ValueError(f"no capillary force law for liquid model {liquid.model!r}")
    ids = particles.ids
    if len(ids) and ids[-1] - ids[0] == len(ids) - 1:
        # contiguous ids (no particle deleted): the row is id - first id, found in the kernel
        a, b, offset = contacts.id1, contacts.id2, int(ids[0])
    else:
        a, b, offset = particles.index_of(contacts.id1), particles.index_of(contacts.id2), 0
    content = particles.liquid_content
    if content is None:
        content = np.full(len(particles), liquid.liquid_content)
    # liquid per particle, m^3: the expression of ligwf.bridges, so bridge volumes agree bitwise
    liquid_volume = 4.0 / 3.0 * np.pi * particles.radii**3 * content
    count, i, j, force = bond_kernel(
        a, b, offset, particles.velocities, particles.radii, liquid_volume,
        np.asarray(contacts.delta, dtype=np.float64), MODEL_CODES[liquid.model],
        float(liquid.surface_tension), float(liquid.contact_angle_rad),
        bridges.WASHINO_BRIDGE_VOLUME_FRACTION,
        math.cos(math.radians(criterion.max_velocity_angle_deg)),
        float(criterion.min_bridge_force))
    if count < 0:       # raises DumpReadError naming the id that is not in the frame
        k = -1 - count
        particles.index_of(np.array([contacts.id1[k], contacts.id2[k]]))
        raise AssertionError("bond_kernel and index_of disagree on the particle rows")
    return i[:count], j[:count], force[:count]


def bonded_contacts_reference(particles: ParticleFrame, contacts: ContactFrame, liquid: Liquid,
                              criterion: BondCriterion = BondCriterion()):
    """:func:`bonded_contacts` evaluated with numpy and :mod:`ligwf.bridges` (the reference)."""
    i = particles.index_of(contacts.id1)
    j = particles.index_of(contacts.id2)
    # the cheap velocity test first; the force law only for the pairs that pass it
    sel = np.flatnonzero(comoving(particles.velocities[i], particles.velocities[j],
                                  criterion.max_velocity_angle_deg))
    i, j = i[sel], j[sel]
    force = _capillary(particles, i, j, -contacts.delta[sel], liquid)
    keep = force > criterion.min_bridge_force
    return i[keep], j[keep], force[keep]


def _is_canonical(labels: np.ndarray) -> bool:
    """True when label k first appears after labels 0..k-1 (then the running maximum
    never jumps by more than one), checked in one pass instead of a sort."""
    if len(labels) == 0:
        return True
    return labels[0] == 0 and bool(np.all(np.diff(np.maximum.accumulate(labels)) <= 1))


def _canonical(labels: np.ndarray) -> np.ndarray:
    """Relabel so granule k is the k-th distinct label met in particle (id) order."""
    if _is_canonical(labels):      # often numbered in this order already
        return labels.astype(np.int64, copy=False)
    _, first, inverse = np.unique(labels, return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    return rank[inverse.reshape(-1)]


def label_reference(n: int, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Granule label per particle by networkx breadth-first search (the reference)."""
    import networkx as nx

    graph = nx.Graph()
    graph.add_nodes_from(range(n))
    graph.add_edges_from(zip(i.tolist(), j.tolist()))
    labels = np.empty(n, dtype=np.int64)
    # nx.connected_components runs a BFS from each not yet visited node in node order;
    # sorting by the smallest member gives the canonical numbering independently of that.
    components = sorted(nx.connected_components(graph), key=min)
    for k, members in enumerate(components):
        labels[list(members)] = k
    return labels


def label_fast(n: int, i: np.ndarray, j: np.ndarray) -> np.ndarray:
    """Granule label per particle by compiled union-find (canonical numbering built in)."""
    from .granules_numba import union_find_labels

    return union_find_labels(int(n), np.asarray(i, dtype=np.int64), np.asarray(j, dtype=np.int64))


def _wrap(d: np.ndarray, length: float) -> np.ndarray:
    """Minimum-image displacement along a periodic axis of ``length`` m."""
    return d - length * np.round(d / length)


def unwrap_reference(positions: np.ndarray, labels: np.ndarray, i: np.ndarray, j: np.ndarray,
                     axis: int, length: float) -> np.ndarray:
    """Positions unwrapped along the bonds (networkx BFS from each granule's first member)."""
    import networkx as nx

    out = positions.copy()
    graph = nx.Graph()
    graph.add_nodes_from(range(len(positions)))
    # lexicographically sorted (lo, hi) edges make every node's neighbour order ascending,
    # the order the compiled BFS (unwrap_fast) uses, so both build the same BFS tree
    graph.add_edges_from(sorted(zip(np.minimum(i, j).tolist(), np.maximum(i, j).tolist())))
    roots = np.unique(labels, return_index=True)[1]
    for root in roots:
        for parent, child in nx.bfs_edges(graph, int(root)):
            d = positions[child, axis] - positions[parent, axis]
            out[child, axis] = out[parent, axis] + d - length * round(d / length)
    return out


def unwrap_fast(positions: np.ndarray, labels: np.ndarray, i: np.ndarray, j: np.ndarray,
                axis: int, length: float) -> np.ndarray:
    """Positions unwrapped along the bonds, compiled (same result as the reference).

    The same breadth-first forest as :func:`unwrap_reference` (one tree per granule, rooted
    at its first member, neighbours in ascending index order) and the same per-edge update,
    so both agree to the last bit, also for a granule that percolates through the periodic
    axis, whose unwrapping depends on the tree. The roots (each granule's first member) are
    found during the search, so ``labels`` is not needed; it is kept for the common
    signature with :func:`unwrap_reference`.
    """
    from .granules_numba import bfs_unwrap

    out = positions.copy()
    if len(i) == 0 or length <= 0:
        return out
    out[:, axis] = bfs_unwrap(np.asarray(positions[:, axis], dtype=np.float64),
                              np.asarray(i, dtype=np.int64), np.asarray(j, dtype=np.int64),
                              float(length))
    return out


def granule_table(particles: ParticleFrame, labels: np.ndarray, cg: float,
                  unwrapped: np.ndarray | None = None, periodic_axis: int | None = 1,
                  box_lo: float = 0.0, box_length: float = 0.0) -> pd.DataFrame:
    """One row per granule: members, volume (m^3), primary-equivalent volume (m^3, volume /
    cg^3), centre of mass (m, wrapped into the periodic box), smallest member id."""
    from .granules_numba import granule_sums

    n_gran = int(labels.max()) + 1 if len(labels) else 0
    pos = particles.positions if unwrapped is None else unwrapped
    members, volume, moment, first = granule_sums(
        np.asarray(labels, dtype=np.int64), n_gran, particles.radii, np.asarray(pos, dtype=np.float64))
    com = moment / volume[:, None]
    if periodic_axis is not None and box_length > 0:
        com[:, periodic_axis] = box_lo + np.mod(com[:, periodic_axis] - box_lo, box_length)
    first_id = particles.ids[first]
    return pd.DataFrame({
        "granule": np.arange(n_gran, dtype=np.int64),
        "members": members.astype(np.int64),
        "volume": volume,
        "primary_volume": volume / float(cg) ** 3,
        "com_x": com[:, 0], "com_y": com[:, 1], "com_z": com[:, 2],
        "first_id": first_id,
    })


def louvain_labels(n: int, i: np.ndarray, j: np.ndarray, force: np.ndarray,
                   seed: int = 0, resolution: float = 1.0) -> np.ndarray:
    """Alternative granules: Louvain communities of the bridge-force-weighted bonded graph.

    Connected components over-merge in a dense wet bed (one cluster holds ~ the whole bed),
    whereas communities split it where bridges are weak relative to the rest. Weights are
    forces normalised by their mean (N / N), so the result does not depend on the CG rule's
    force scale. Labels are canonical like :func:`label_fast`; singletons stay singletons.
    """
    import networkx as nx

    graph = nx.Graph()
    graph.add_nodes_from(range(n))
    w = force / force.mean() if len(force) else force
    graph.add_weighted_edges_from(zip(i.tolist(), j.tolist(), w.tolist()))
    labels = np.empty(n, dtype=np.int64)
    for k, members in enumerate(nx.community.louvain_communities(
            graph, weight="weight", resolution=resolution, seed=seed)):
        labels[list(members)] = k
    return _canonical(labels)
