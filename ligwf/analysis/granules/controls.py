"""Granule controls: does a definition find bodies that move together and survive?

Any partition of a dense bed into patches passes "no percolation", "robust to thresholds"
and "responds to the liquid" (a CPM tiling does). What a granule is: a body whose members
stay together and move together, which a bed without cohesion does not have. The measures
here are pure functions of per-particle granule labels (one integer per particle row,
rows in id order; singletons are granules of one) and positions, so every definition is
judged by the same code, on a wet bed and on its cohesionless twin:

* :func:`bed_share` -- share of the bed's volume in granules of >= k particles;
* :func:`pair_persistence` -- of the particle pairs that share a granule at t, the share
  still sharing one at t + dt (counted through the contingency table of the two
  partitions, so a granule of s members counts its s(s-1)/2 pairs without listing them);
* :func:`comovement` -- how fast the distance of member pairs changes over tau, against
  non-member pairs at the same initial distance (matched in distance bins);
* :func:`adjusted_rand_index` -- agreement of two partitions of the same frame (Hubert and
  Arabie 1985), for optimiser seeds and contact-row orders.
"""

from __future__ import annotations

from dataclasses import dataclass

import numpy as np

#: distance bins of :func:`comovement`, in mean particle diameters (centre distance)
COMOVEMENT_BINS = (0.0, 1.05, 1.25, 1.5, 2.0, 3.0, 4.0, 6.0)


def _pairs(counts: np.ndarray) -> float:
    """sum of c (c - 1) / 2 over the counts (pairs inside each class), as a float."""
    c = np.asarray(counts, dtype=np.float64)
    return float(np.sum(c * (c - 1.0)) / 2.0)


def _contingency(a: np.ndarray, b: np.ndarray) -> np.ndarray:
    """Counts of the (label a, label b) combinations that occur (a sparse contingency table)."""
    a = np.asarray(a, dtype=np.int64)
    b = np.asarray(b, dtype=np.int64)
    if len(a) != len(b):
        raise ValueError(f"partitions of {len(a)} and {len(b)} particles")
    if not len(a):
        return np.zeros(0, dtype=np.int64)
    key = a * (int(b.max()) + 1) + b
    return np.unique(key, return_counts=True)[1]


def adjusted_rand_index(a: np.ndarray, b: np.ndarray) -> float:
    """Adjusted Rand index of two partitions of the same particles (1: identical up to
    label names; ~0: no better than chance). Two partitions into singletons only, or both
    into one class, agree perfectly (1.0)."""
    a = np.asarray(a)
    b = np.asarray(b)
    n = len(a)
    if n < 2:
        return 1.0
    index = _pairs(_contingency(a, b))
    sum_a = _pairs(np.unique(a, return_counts=True)[1])
    sum_b = _pairs(np.unique(b, return_counts=True)[1])
    total = n * (n - 1) / 2.0
    expected = sum_a * sum_b / total
    maximum = 0.5 * (sum_a + sum_b)
    if maximum == expected:
        return 1.0
    return float((index - expected) / (maximum - expected))


def pair_persistence(labels_t: np.ndarray, labels_u: np.ndarray) -> float:
    """Of the particle pairs sharing a granule at t, the share still sharing one at u
    (nan when no two particles share a granule at t). Rows are the same particles."""
    together_t = _pairs(np.unique(labels_t, return_counts=True)[1])
    if together_t == 0:
        return float("nan")
    return _pairs(_contingency(labels_t, labels_u)) / together_t


def granule_sizes(labels: np.ndarray) -> np.ndarray:
    """Members of each particle's granule (per particle row)."""
    labels = np.asarray(labels, dtype=np.int64)
    if not len(labels):
        return np.zeros(0, dtype=np.int64)
    _, inverse, counts = np.unique(labels, return_inverse=True, return_counts=True)
    return counts[inverse]


def bed_share(labels: np.ndarray, volumes: np.ndarray, min_particles: int) -> float:
    """Share of the bed's particle volume in granules of >= ``min_particles`` members."""
    volumes = np.asarray(volumes, dtype=np.float64)
    inside = granule_sizes(labels) >= min_particles
    total = float(volumes.sum())
    return float(volumes[inside].sum() / total) if total > 0 else float("nan")


def volume_d50(labels: np.ndarray, volumes: np.ndarray, min_particles: int) -> float:
    """Volume-weighted median granule volume of the granules of >= ``min_particles``
    members, as the diameter of the sphere of that volume, m (nan: no such granule)."""
    labels = np.asarray(labels, dtype=np.int64)
    if not len(labels):
        return float("nan")
    uniq, inverse = np.unique(labels, return_inverse=True)
    gv = np.bincount(inverse, weights=volumes, minlength=len(uniq))
    members = np.bincount(inverse, minlength=len(uniq))
    gv = np.sort(gv[members >= min_particles])
    if not len(gv):
        return float("nan")
    cum = np.cumsum(gv) / gv.sum()
    median_volume = gv[int(np.searchsorted(cum, 0.5))]
    return float((6.0 * median_volume / np.pi) ** (1.0 / 3.0))


def granule_count(labels: np.ndarray, min_particles: int) -> int:
    """Granules of >= ``min_particles`` members."""
    labels = np.asarray(labels, dtype=np.int64)
    if not len(labels):
        return 0
    counts = np.unique(labels, return_counts=True)[1]
    return int(np.sum(counts >= min_particles))


@dataclass(frozen=True)
class Comovement:
    """Growth of pair distances over tau: members of one granule against non-members at the
    same initial distance (each bin weighted by its member pairs)."""

    member_growth: float       # m, mean |d(t + tau) - d(t)| of member pairs
    nonmember_growth: float    # m, the same for non-members, matched bin by bin
    member_pairs: int

    @property
    def ratio(self) -> float:
        """member / non-member growth (<< 1: members move together; ~1: a tiling)."""
        if not self.nonmember_growth > 0:
            return float("nan")
        return self.member_growth / self.nonmember_growth


def _min_image(d: np.ndarray, axis: int | None, length: float) -> np.ndarray:
    if axis is not None and length > 0:
        d = d.copy()
        d[:, axis] -= length * np.round(d[:, axis] / length)
    return d


def comovement(labels: np.ndarray, pos_t: np.ndarray, pos_u: np.ndarray, diameter: float,
               periodic_axis: int | None, length: float,
               bins: tuple[float, ...] = COMOVEMENT_BINS) -> Comovement:
    """:class:`Comovement` of the granules ``labels`` at t, positions at t and u = t + tau
    (m; rows the same particles), pairs within ``bins`` (mean diameters ``diameter``, m) of
    each other at t, distances by the nearest periodic image."""
    from scipy.spatial import cKDTree

    pos_t = np.asarray(pos_t, dtype=np.float64)
    pos_u = np.asarray(pos_u, dtype=np.float64)
    edges = np.asarray(bins, dtype=np.float64) * diameter
    lo = pos_t.min(axis=0)
    pts = pos_t - lo
    box = pts.max(axis=0) + 2.0 * edges[-1] + 1.0
    if periodic_axis is not None and length > 0:
        pts[:, periodic_axis] = np.mod(pos_t[:, periodic_axis], length)
        box[periodic_axis] = length
    pairs = cKDTree(pts, boxsize=box).query_pairs(edges[-1], output_type="ndarray")
    if not len(pairs):
        return Comovement(float("nan"), float("nan"), 0)
    a, b = pairs[:, 0], pairs[:, 1]
    d_t = np.linalg.norm(_min_image(pos_t[b] - pos_t[a], periodic_axis, length), axis=1)
    d_u = np.linalg.norm(_min_image(pos_u[b] - pos_u[a], periodic_axis, length), axis=1)
    growth = np.abs(d_u - d_t)
    member = np.asarray(labels)[a] == np.asarray(labels)[b]
    which = np.digitize(d_t, edges) - 1
    m_sum = n_sum = weight = 0.0
    for k in range(len(edges) - 1):
        in_bin = which == k
        mem, non = in_bin & member, in_bin & ~member
        if mem.sum() == 0 or non.sum() == 0:
            continue
        w = float(mem.sum())
        m_sum += w * float(growth[mem].mean())
        n_sum += w * float(growth[non].mean())
        weight += w
    if weight == 0:
        return Comovement(float("nan"), float("nan"), int(member.sum()))
    return Comovement(m_sum / weight, n_sum / weight, int(weight))
