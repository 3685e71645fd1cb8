"""Compiled (numba) kernels of the granule fast path: bond test, union-find, unwrap, table.

Why compiled: at 360k particles and ~900k contacts the numpy bond test allocates a dozen
temporaries of the contact length and evaluates both branches of the force law for every
pair, and scipy's components and BFS build sparse matrices first; that alone is tens of
times the cost of streaming the contact arrays once. Each kernel here is one loop over its
data instead, evaluating exactly the formulas of :mod:`ligwf.bridges` (same expressions, so
the same bonds; the tests compare every kernel with the numpy / networkx reference on real
dumps and random graphs).

``cache=True`` stores the machine code next to this file (``__pycache__``), so the few
seconds of compilation are paid once per installation, not once per process; call
:func:`warm_up` before timing anything.
"""

from __future__ import annotations

import math

import numpy as np
from numba import njit

#: liquid model codes of :func:`bond_kernel`
MODEL_CODES = {"none": 0, "washino": 1, "easo": 2}


@njit(cache=True, inline="always", error_model="numpy")
def _within_rupture(gap, vol, theta, rupture_cube_factor):
    """``gap < (1 + theta/2) vol^(1/3)`` (:func:`ligwf.bridges.rupture_distance`) decided
    without the cube root where the cubes differ by more than any rounding could (1e-10
    relative); the few pairs closer than that get the exact comparison. Written with
    non-short-circuit ``&``/``|`` so the compiler can avoid branches on random gaps."""
    separated = gap > 0.0
    g3, r3 = gap * gap * gap, rupture_cube_factor * vol
    sure_in = (gap < 0.0) | (separated & (g3 < r3 * (1.0 - 1e-10)))
    sure_out = separated & (g3 > r3 * (1.0 + 1e-10))
    if sure_in | sure_out:
        return sure_in
    return gap < (1.0 + 0.5 * theta) * np.cbrt(vol)


@njit(cache=True, error_model="numpy")
def _washino_force(ri, rj, gap, gamma, cos_theta, sin_theta, vol):
    """:func:`ligwf.bridges.washino_capillary_force` for one pair within rupture, N;
    ``vol``: the bridge volume, m^3 (:func:`ligwf.bridges.washino_bridge_volume`)."""
    r_eff = ri * rj / (ri + rj)
    if gap <= 0.0:
        return 2 * np.pi * r_eff * gamma * cos_theta * (
            1.0 - gap * math.sqrt(np.pi * r_eff / (2.0 * vol)))
    p = -1.0 + math.sqrt(1.0 + 2.0 * vol / (np.pi * r_eff * gap**2))
    d_sp = 0.5 * gap * p
    alpha = math.sqrt(gap / r_eff * p)
    sin_alpha = math.sin(alpha)
    # sin(alpha + theta) by the addition theorem: one sine call instead of two (the same
    # value to rounding, ~1e-16 relative); cos(alpha) >= 0 while alpha <= pi/2
    cos_alpha = math.sqrt(1.0 - sin_alpha * sin_alpha) if alpha <= 0.5 * np.pi else math.cos(alpha)
    return 2 * np.pi * r_eff * gamma * (
        cos_theta / (1.0 + gap / (2.0 * d_sp))
        + sin_alpha * (sin_alpha * cos_theta + cos_alpha * sin_theta))


@njit(cache=True, error_model="numpy")
def _easo_volume(ri, rj, wi, wj):
    """:func:`ligwf.bridges.easo_bridge_volume` from each partner's liquid volume, m^3."""
    s = ri + rj
    cap_i = 0.5 * (1.0 - math.sqrt(1.0 - rj**2 / s**2))
    cap_j = 0.5 * (1.0 - math.sqrt(1.0 - ri**2 / s**2))
    return wi * cap_i + wj * cap_j


@njit(cache=True, error_model="numpy")
def _easo_force(ri, rj, gap, gamma, theta, vol):
    """:func:`ligwf.bridges.easo_capillary_force` for one pair within rupture, N."""
    r2 = max(ri, rj)
    vs = vol / r2**3
    log_vs = math.log(vs)
    a = -1.1 * vs ** (-0.53)
    b = (-0.148 * log_vs - 0.96) * theta**2 - 0.0082 * log_vs + 0.48
    c = 0.0018 * log_vs + 0.078
    expo = a * gap / r2 + b if gap > 0.0 else b
    return np.pi * gamma * math.sqrt(ri * rj) * (math.exp(expo) + c)


@njit(cache=True, error_model="numpy")
def bond_kernel(id1, id2, id_offset, velocities, radii, liquid_volume, delta, model, gamma,
                theta, fraction, cos_max, min_force):
    """One pass over the contacts: rupture distance and velocity angle, then the force law.

    A pair beyond rupture has no bridge (force 0, never above ``min_force`` >= 0), so the
    two cheap tests come first and the force law runs only for pairs that pass both.

    Particle rows are ``id1 - id_offset`` and ``id2 - id_offset`` (the ids themselves when
    the caller already mapped them, with offset 0). ``liquid_volume``: sphere volume x
    liquid content per particle, m^3, computed by the caller with the numpy expression of
    :mod:`ligwf.bridges` so that the bridge volumes agree to the last bit. Returns
    (count, i, j, force) with the bonded pairs in the first ``count`` entries, or
    count = -1 - k when contact k refers to a row outside the frame.
    """
    m = len(id1)
    n = len(radii)
    out_i = np.empty(m, np.int64)
    out_j = np.empty(m, np.int64)
    out_f = np.empty(m, np.float64)
    count = 0
    if model == 0:
        return count, out_i, out_j, out_f
    cos_theta, sin_theta = math.cos(theta), math.sin(theta)
    cube_factor = (1.0 + 0.5 * theta) ** 3
    for k in range(m):
        a = np.int64(id1[k]) - id_offset
        b = np.int64(id2[k]) - id_offset
        if a < 0 or a >= n or b < 0 or b >= n:
            return -1 - k, out_i, out_j, out_f
        gap = -delta[k]
        ra, rb = radii[a], radii[b]
        if model == 1:
            vol = fraction * (liquid_volume[a] + liquid_volume[b])
        else:
            vol = _easo_volume(ra, rb, liquid_volume[a], liquid_volume[b])
        vax, vay, vaz = velocities[a, 0], velocities[a, 1], velocities[a, 2]
        vbx, vby, vbz = velocities[b, 0], velocities[b, 1], velocities[b, 2]
        dot = vax * vbx + vay * vby + vaz * vbz
        norms = math.sqrt((vax * vax + vay * vay + vaz * vaz) * (vbx * vbx + vby * vby + vbz * vbz))
        comoving = (norms == 0.0) | (dot >= cos_max * norms)
        # beyond rupture there is no bridge (force 0, never above min_force >= 0)
        if not (comoving & _within_rupture(gap, vol, theta, cube_factor)):
            continue
        if model == 1:
            f = _washino_force(ra, rb, gap, gamma, cos_theta, sin_theta, vol)
        else:
            f = _easo_force(ra, rb, gap, gamma, theta, vol)
        if f > min_force:
            out_i[count] = a
            out_j[count] = b
            out_f[count] = f
            count += 1
    return count, out_i, out_j, out_f


@njit(cache=True, inline="always")
def _find(parent, x):
    while parent[x] != x:
        parent[x] = parent[parent[x]]      # path halving
        x = parent[x]
    return x


@njit(cache=True)
def union_find_labels(n, i, j):
    """Connected components by union-find; labels numbered in order of first member, so
    granule 0 holds particle 0, granule 1 the first particle not in granule 0, and so on."""
    parent = np.arange(n)
    for k in range(len(i)):
        a = _find(parent, i[k])
        b = _find(parent, j[k])
        if a < b:
            parent[b] = a
        elif b < a:
            parent[a] = b
    labels = np.empty(n, np.int64)
    label_of_root = np.full(n, -1, np.int64)
    next_label = 0
    for x in range(n):
        r = _find(parent, x)
        if label_of_root[r] < 0:
            label_of_root[r] = next_label
            next_label += 1
        labels[x] = label_of_root[r]
    return labels


@njit(cache=True)
def _adjacency(n, i, j):
    """CSR adjacency (row starts, int32 neighbours) of the undirected edges, rows unsorted."""
    start = np.zeros(n + 1, np.int64)
    for k in range(len(i)):
        start[i[k] + 1] += 1
        start[j[k] + 1] += 1
    for x in range(n):
        start[x + 1] += start[x]
    fill = start[:-1].copy()
    nbr = np.empty(start[n], np.int32)
    for k in range(len(i)):
        a, b = i[k], j[k]
        nbr[fill[a]] = b
        fill[a] += 1
        nbr[fill[b]] = a
        fill[b] += 1
    return start, nbr


@njit(cache=True, error_model="numpy")
def bfs_unwrap(y, i, j, length):
    """Coordinate ``y`` unwrapped along the bonds: breadth-first from each granule's first
    member, neighbours in ascending order (the tree of :func:`ligwf.granules.unwrap_reference`),
    each child placed at its parent plus the minimum-image displacement.

    The adjacency rows are not sorted; instead the children a node discovers (its
    not yet visited neighbours, about one per node in a tree) are sorted as they are queued,
    which puts them in the queue in the same order as scanning sorted rows would.
    """
    n = len(y)
    start, nbr = _adjacency(n, i, j)
    out = np.full(n, np.nan)                  # nan: not reached yet (positions are finite)
    queue = np.empty(n, np.int32)
    for root in range(n):
        if not np.isnan(out[root]):           # the first unreached particle in index order
            continue                          # is the first member of the next granule
        out[root] = y[root]
        head, tail = 0, 1
        queue[0] = root
        while head < tail:
            u = queue[head]
            head += 1
            yu, ou = y[u], out[u]
            first_child = tail
            for p in range(start[u], start[u + 1]):
                v = nbr[p]
                if np.isnan(out[v]):
                    d = y[v] - yu
                    out[v] = ou + d - length * np.rint(d / length)
                    q = tail                   # insertion into the sorted run of children
                    while q > first_child and queue[q - 1] > v:
                        queue[q] = queue[q - 1]
                        q -= 1
                    queue[q] = v
                    tail += 1
    return out


@njit(cache=True, error_model="numpy")
def granule_sums(labels, n_granules, radii, positions):
    """Members, volume (m^3), volume-weighted position sums (m^4) and first member (row)
    per granule, in one pass (the same sums, in the same order, as numpy.bincount)."""
    members = np.zeros(n_granules, np.int64)
    first = np.zeros(n_granules, np.int64)
    volume = np.zeros(n_granules)
    moment = np.zeros((n_granules, 3))
    for x in range(len(labels)):
        g = labels[x]
        v = 4.0 / 3.0 * np.pi * radii[x] ** 3
        if members[g] == 0:
            first[g] = x
        members[g] += 1
        volume[g] += v
        moment[g, 0] += v * positions[x, 0]
        moment[g, 1] += v * positions[x, 1]
        moment[g, 2] += v * positions[x, 2]
    return members, volume, moment, first


def warm_up() -> None:
    """Compile (or load from the cache) every kernel on a two-particle frame."""
    v = np.ones((2, 3))
    r, c = np.full(2, 1e-3), np.full(2, 0.02)
    for model in (1, 2):
        bond_kernel(np.array([1]), np.array([2]), 1, v, r, r**3, np.array([1e-6]), model,
                    0.02, 0.1, 0.05, 0.5, 0.0)
    i, j = np.array([0]), np.array([1])
    labels = union_find_labels(2, i, j)
    bfs_unwrap(v[:, 1].copy(), i, j, 1.0)
    granule_sums(labels, 1, r, v)
