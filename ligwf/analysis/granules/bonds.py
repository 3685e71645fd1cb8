"""Granule identification: liquid-bonded contacts -> connected components -> granule table.

A contact of the contact dump is a *liquid bond* when (criteria after Dong et al., as used
by the source study):

1. its liquid-bridge (capillary, cohesive) force exceeds ``min_bridge_force`` (N), and
2. the angle between the two partners' velocity vectors is below ``max_velocity_angle_deg``.

The bridge force is evaluated from the geometry with the engine's own law (the case's
model in :mod:`ligwf.liquids`, verified against LIGGGHTS to 1e-9) from the
dumped overlap ``delta`` (gap = -delta), the radii and the liquid content of both
partners: the dumped total force cannot be used directly because for touching pairs it
includes the Hertz repulsion. Separated pairs (delta < 0) within the rupture distance
carry a bridge and count; beyond rupture the law gives 0 and the pair is not bonded.

Granules are the connected components of the bonded graph (built on particle ids, never on
geometry, since pairs across the periodic boundary span the box). Two implementations of
:func:`identify`: :func:`identify_reference` (compiled bond test, then networkx BFS for
the components and for the unwrapping: the method of the source study, slow, obviously
right) and :func:`identify_fast` (bond test, union-find and unwrapping in one compiled pass
over the contacts, :mod:`ligwf.analysis.granules_numba`); both return the same canonical labels
(granule 0 holds the particle with the smallest id, and so on), which the tests check on
real dumps and on random graphs. The numpy evaluation of the bond criterion,
:func:`bonded_contacts_reference`, is kept as the reference of the compiled one.

Centres of mass are computed with positions unwrapped along the bonds across the
periodic axis (a granule straddling y = 0 / y = L has its centre inside it, not in the
middle of the box), then wrapped back into the box. A granule that closes a cycle around
the periodic axis (*percolating*, common for the big cluster of a dense wet bed) has no
unwrapped layout; its members stay in the box and its centre along the axis is the plain
mean of their in-box positions (flagged ``percolating`` in the table). All
particles of a ligwf scene share one density, so centres of mass are volume-weighted.
"""

from __future__ import annotations

import math
from dataclasses import dataclass

import numpy as np
import pandas as pd

from ligwf.analysis.granules.bridge_law import Liquid, content_of, force_law_positive, pair_forces
from ligwf.analysis.frames.dumps import ContactFrame, ParticleFrame



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


def comoving(v_i: np.ndarray, v_j: np.ndarray, max_angle_deg: float) -> np.ndarray:
    """True where the angle between v_i and v_j (rows, m/s) is <= max_angle_deg.

    Compared as cos(angle) >= cos(max) without arccos; a zero velocity counts as co-moving.
    """
    dot = np.einsum("ij,ij->i", v_i, v_j)
    norms = np.sqrt(np.einsum("ij,ij->i", v_i, v_i) * np.einsum("ij,ij->i", v_j, v_j))
    return (norms == 0.0) | (dot >= math.cos(math.radians(max_angle_deg)) * norms)


def _kernel_args(particles: ParticleFrame, contacts: ContactFrame, liquid: Liquid,
                 criterion: BondCriterion) -> tuple[tuple, np.ndarray]:
    """The leading arguments shared by the compiled bond kernels (:func:`bond_kernel
    <ligwf.analysis.granules_numba.bond_kernel>`, :func:`bond_components
    <ligwf.analysis.granules_numba.bond_components>`), and the liquid content per particle (the
    scene's when the dump lacks it). Contacts go in as rows, or as ids with their offset
    when the ids are contiguous (the kernel then maps them itself)."""
    from ligwf.analysis.granules_numba import law

    ids = particles.ids
    if len(ids) and ids[-1] - ids[0] == len(ids) - 1:
        # contiguous ids (no particle deleted): the row is id - first id, found in the kernel
        a, b, offset = contacts.id1, contacts.id2, int(ids[0])
    else:
        a, b, offset = particles.index_of(contacts.id1), particles.index_of(contacts.id2), 0
    content = content_of(particles, liquid)
    args = (a, b, offset, particles.velocities, particles.radii, content,
            np.asarray(contacts.delta, dtype=np.float64), *law(liquid.law),
            float(liquid.surface_tension), float(liquid.contact_angle_rad),
            math.cos(math.radians(criterion.max_velocity_angle_deg)),
            float(criterion.min_bridge_force))
    return args, content


def _unknown_id(particles: ParticleFrame, contacts: ContactFrame, count: int) -> None:
    """A kernel reported contact ``-1 - count`` outside the frame: raise DumpReadError
    naming the id (index_of does)."""
    k = -1 - count
    particles.index_of(np.array([contacts.id1[k], contacts.id2[k]]))
    raise AssertionError("bond kernel and index_of disagree on the particle rows")


def bonded_contacts(particles: ParticleFrame, contacts: ContactFrame, liquid: Liquid,
                    criterion: BondCriterion = BondCriterion(), with_rows: bool = False):
    """Indices (i, j) of bonded pairs into the particle arrays, and their bridge forces (N)
    (``with_rows``: also each bond's row in the contact dump).

    One compiled pass over the contacts (:func:`ligwf.analysis.granules_numba.bond_kernel`): the
    rupture distance and velocity-angle tests, then the force law of the liquid model only
    for the pairs that pass both; pairs in contact order. The same pairs as
    :func:`bonded_contacts_reference`, forces equal to rounding (~1e-16 relative), tested
    on real dumps and random frames.
    """
    from ligwf.analysis.granules_numba import bond_kernel

    args, _ = _kernel_args(particles, contacts, liquid, criterion)
    count, i, j, force, rows = bond_kernel(*args)
    if count < 0:
        _unknown_id(particles, contacts, count)
    if with_rows:
        return i[:count], j[:count], force[:count], rows[:count]
    return i[:count], j[:count], force[:count]


def bonded_contacts_reference(particles: ParticleFrame, contacts: ContactFrame, liquid: Liquid,
                              criterion: BondCriterion = BondCriterion(),
                              with_rows: bool = False):
    """:func:`bonded_contacts` evaluated with numpy and the model's numpy law (the reference)."""
    i = particles.index_of(contacts.id1)
    j = particles.index_of(contacts.id2)
    # the cheap velocity test first; the force law only for the pairs that pass it
    sel = np.flatnonzero(comoving(particles.velocities[i], particles.velocities[j],
                                  criterion.max_velocity_angle_deg))
    i, j = i[sel], j[sel]
    force = pair_forces(particles, i, j, -contacts.delta[sel], liquid)
    keep = force > criterion.min_bridge_force
    if with_rows:
        return i[keep], j[keep], force[keep], sel[keep]
    return i[keep], j[keep], force[keep]


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
    from ligwf.analysis.granules_numba import union_find_labels

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
    # lexicographically sorted (lo, hi) edges make every node's neighbour order ascending
    # (a deterministic tree: the same result on every run)
    graph.add_edges_from(sorted(zip(np.minimum(i, j).tolist(), np.maximum(i, j).tolist())))
    roots = np.unique(labels, return_index=True)[1]
    for root in roots:
        for parent, child in nx.bfs_edges(graph, int(root)):
            d = positions[child, axis] - positions[parent, axis]
            out[child, axis] = out[parent, axis] + d - length * round(d / length)
    return out


def percolating_reference(labels: np.ndarray, unwrapped: np.ndarray, i: np.ndarray,
                          j: np.ndarray, axis: int, length: float) -> np.ndarray:
    """Per granule: does it close a cycle around the periodic axis? True when one of its
    bonds, laid out by the unwrapped positions, is not the minimum-image displacement."""
    n_gran = int(labels.max()) + 1 if len(labels) else 0
    out = np.zeros(n_gran, dtype=bool)
    if len(i) and length > 0:
        y = unwrapped[:, axis]
        laid_out = y[j] - y[i]
        direct = _wrap(y[j] - y[i], length)
        out[labels[i[np.abs(laid_out - direct) > 0.5 * length]]] = True
    return out


@dataclass(frozen=True)
class Identification:
    """Granules of one frame.

    ``i``, ``j``: bonded pairs (rows of the particle arrays) in contact order; ``force``:
    their bridge forces, N (None when not evaluated, see :func:`identify`); ``labels``:
    canonical granule per particle; ``unwrapped_axis``: the coordinate along the periodic
    axis ``axis``, laid out along the bonds (None without a periodic axis; the other two
    coordinates never change); ``percolating``: per granule, True when it closes a cycle
    around the periodic axis (it spans the whole box along it and has no unwrapped layout:
    its members keep their in-box positions, see :func:`granule_table`).
    """

    i: np.ndarray
    j: np.ndarray
    force: np.ndarray | None
    labels: np.ndarray
    axis: int | None
    unwrapped_axis: np.ndarray | None
    percolating: np.ndarray

    def unwrapped(self, positions: np.ndarray) -> np.ndarray:
        """All three coordinates, the periodic one unwrapped (a copy; for output and tests)."""
        out = np.array(positions, dtype=float, copy=True)
        if self.axis is not None and self.unwrapped_axis is not None:
            out[:, self.axis] = self.unwrapped_axis
        return out


def identify_fast(particles: ParticleFrame, contacts: ContactFrame, liquid: Liquid,
                  criterion: BondCriterion = BondCriterion(), periodic_axis: int | None = 1,
                  length: float = 0.0, need_force: bool = False) -> Identification:
    """Bonds, granules and unwrapping in one compiled pass over the contacts
    (:func:`ligwf.analysis.granules_numba.bond_components`). The force law is evaluated only when it
    can change the verdict (``min_bridge_force`` > 0, or a law not provably positive) or
    when the caller asks for the forces (``need_force``, e.g. for Louvain weights)."""
    from ligwf.analysis.granules_numba import bond_components

    args, content = _kernel_args(particles, contacts, liquid, criterion)
    force_needed = (need_force or criterion.min_bridge_force > 0.0
                    or not force_law_positive(particles, liquid, content))
    axis = 1 if periodic_axis is None else periodic_axis
    period = float(length) if periodic_axis is not None else 0.0
    y = np.ascontiguousarray(particles.positions[:, axis], dtype=np.float64)
    count, i, j, force, labels, y_out, percolating, _ = bond_components(
        *args, force_needed, y, period)
    if count < 0:
        _unknown_id(particles, contacts, count)
    return Identification(i[:count], j[:count], force[:count] if force_needed else None,
                          labels, periodic_axis if period > 0.0 else None,
                          y_out if period > 0.0 else None, percolating)


def identify_reference(particles: ParticleFrame, contacts: ContactFrame, liquid: Liquid,
                       criterion: BondCriterion = BondCriterion(), periodic_axis: int | None = 1,
                       length: float = 0.0, need_force: bool = True) -> Identification:
    """The reference: the shared bond test, networkx BFS components, networkx BFS unwrap."""
    i, j, force = bonded_contacts(particles, contacts, liquid, criterion)
    return components(particles.positions, i, j, force, periodic_axis, length, "reference")


def components(positions: np.ndarray, i: np.ndarray, j: np.ndarray, force: np.ndarray | None,
               periodic_axis: int | None, length: float,
               implementation: str = "fast") -> Identification:
    """Granules = connected components of the given bonds (rows i, j; ``force`` N is only
    carried along), unwrapped along the periodic axis, percolation per granule: compiled
    union-find (``fast``, :func:`ligwf.analysis.granules_numba.components_images`) or
    networkx BFS (``reference``); the same canonical labels."""
    n = len(positions)
    periodic = periodic_axis is not None and length > 0
    if implementation == "fast":
        from ligwf.analysis.granules_numba import components_images

        y = np.ascontiguousarray(positions[:, periodic_axis if periodic else 1], np.float64)
        labels, y_out, percolating, _ = components_images(
            n, np.asarray(i, np.int64), np.asarray(j, np.int64), len(i), y,
            float(length) if periodic else 0.0)
        return Identification(i, j, force, labels, periodic_axis if periodic else None,
                              y_out if periodic else None, percolating)
    labels = label_reference(n, i, j)
    if not periodic:
        n_gran = int(labels.max()) + 1 if len(labels) else 0
        return Identification(i, j, force, labels, None, None, np.zeros(n_gran, bool))
    unwrapped = unwrap_reference(positions, labels, i, j, periodic_axis, length)
    percolating = percolating_reference(labels, unwrapped, i, j, periodic_axis, length)
    stay = percolating[labels]            # no unwrapped layout: members stay in the box
    unwrapped[stay, periodic_axis] = positions[stay, periodic_axis]
    return Identification(i, j, force, labels, periodic_axis, unwrapped[:, periodic_axis].copy(),
                          percolating)


def identify(particles: ParticleFrame, contacts: ContactFrame, liquid: Liquid,
             criterion: BondCriterion = BondCriterion(), periodic_axis: int | None = 1,
             length: float = 0.0, implementation: str = "fast",
             need_force: bool = False) -> Identification:
    """Granules of one frame by the ``fast`` (default) or ``reference`` implementation."""
    fn = {"fast": identify_fast, "reference": identify_reference}.get(implementation)
    if fn is None:
        raise ValueError(f"implementation {implementation!r}: use fast or reference")
    return fn(particles, contacts, liquid, criterion, periodic_axis, length, need_force)


def granule_table(particles: ParticleFrame, labels: np.ndarray, cg: float,
                  unwrapped_axis: np.ndarray | None = None, periodic_axis: int | None = 1,
                  box_lo: float = 0.0, box_length: float = 0.0,
                  percolating: np.ndarray | None = None) -> pd.DataFrame:
    """One row per granule: members, volume (m^3), primary-equivalent volume (m^3, volume /
    cg^3), centre of mass (m, wrapped into the periodic box), smallest member id, and
    whether it percolates along the periodic axis. ``unwrapped_axis``: the coordinate along
    ``periodic_axis`` laid out along the bonds (:class:`Identification`); None: as dumped.

    A percolating granule wraps around the periodic axis: unwrapping it along its bonds
    would depend on the path taken, so both implementations leave its members in the box
    and its centre along that axis is the plain mean of their in-box positions (about the
    box middle for a granule spread along the whole axis; only the flag is meaningful).
    """
    from ligwf.analysis.granules_numba import granule_sums

    n_gran = int(labels.max()) + 1 if len(labels) else 0
    replace = periodic_axis is not None and unwrapped_axis is not None
    members, volume, moment, first = granule_sums(
        np.asarray(labels, dtype=np.int64), n_gran, particles.radii,
        np.asarray(particles.positions, dtype=np.float64), periodic_axis if replace else -1,
        np.asarray(unwrapped_axis, dtype=np.float64) if replace else np.empty(0))
    com = moment / volume[:, None]
    perc = np.zeros(n_gran, dtype=bool) if percolating is None else np.asarray(percolating, bool)
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
        "percolating": perc,
    })
