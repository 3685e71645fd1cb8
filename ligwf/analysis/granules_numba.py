"""Compiled (numba) kernels of the granule fast path: bond test + union-find + unwrap, table.

Why compiled: at 360k particles and ~900k contacts the numpy bond test allocates a dozen
temporaries of the contact length and evaluates both branches of the force law for every
pair, and scipy's components and BFS build sparse matrices first; that alone is tens of
times the cost of streaming the contact arrays once. Each kernel here is one loop over its
data instead. The liquid model's law comes in as arguments: its numba functions
(:func:`law`, from the model's own module in :mod:`ligwf.liquids`, the same expressions as
its numpy version, so the same bonds; the tests compare every kernel with the numpy /
networkx reference on real dumps and random graphs). numba compiles one loop per model
with the law inlined, as fast as a loop written for one model. :func:`bond_components`
goes further and decides the bonds, merges the granules and unwraps them across the
periodic axis in one call: the unwrapping rides on the union-find (image counts), so no
second search over the bonds is needed.

``cache=True`` stores the machine code next to this file (``__pycache__``, or where
:mod:`ligwf.numba_cache` finds a writable place), so the compilation is paid once per
installation, not once per process and MPI rank. The kernels that evaluate a model's law
(:func:`bond_kernel`, :func:`bond_components`, :func:`rupture_work`) take the law's
functions as arguments, but the compiled code does not: for each law they dispatch to a
kernel of their own, compiled with the law's functions as globals
(:func:`ligwf.numba_cache.specialised`) and cached under a name carrying a digest of the
law's source files (a kernel taking functions as arguments could never be cached: numba
keys it by the function objects, new in every process). :func:`warm_up` compiles or loads
them; call it before timing anything.
"""

from __future__ import annotations

import math
from typing import Callable

import numpy as np
from numba import njit

from ligwf import liquids
from ligwf.numba_cache import cached_jit, law_digest, specialised
from ligwf.analysis.pair_table_numba import find_slot, new_table, remember
from ligwf.liquids.base import LiquidModel


def law(model: LiquidModel) -> tuple:
    """The kernels' law arguments for ``model``: (volume, within_rupture, force)."""
    k = model.kernels
    return (k.volume, k.within_rupture, k.force)

@njit(inline="always", error_model="numpy")
def _bond(a, b, gap, velocities, radii, content, volume, within_rupture, force, gamma, theta,
          cos_theta, sin_theta, cos_max, min_force, force_needed):
    """Bridge force of contact (a, b) if it is a liquid bond, else -1.0.

    ``volume``, ``within_rupture``, ``force``: the liquid model's numba functions
    (``ligwf.liquids.base.Kernels``); each model gets its own compiled loop.
    The two cheap tests first: the rupture distance (beyond it there is no bridge: force
    0, never above ``min_force`` >= 0), then, only for pairs within it, the velocity angle
    (real branches: a pair out of range costs no velocity loads; measured 2.3x faster on a
    360k frame than evaluating both tests for every pair). The force law runs only for
    pairs that pass both, and only when ``force_needed``; otherwise a bond is reported with
    force NaN (the caller has proved the law positive for every pair within rupture and
    ``min_force`` is 0, so the law could not change the verdict).
    """
    ra, rb = radii[a], radii[b]
    # liquid per particle, m^3: the expression of ligwf.liquids.base.sphere_volume x content,
    # operation for operation, so bridge volumes agree with the numpy reference bitwise
    lva = 4.0 / 3.0 * np.pi * (ra * ra * ra) * content[a]
    lvb = 4.0 / 3.0 * np.pi * (rb * rb * rb) * content[b]
    if not lva + lvb > 0.0:
        return -1.0            # two dry particles: no liquid, no bridge (placed liquid)
    vol = volume(ra, rb, lva, lvb)
    if not within_rupture(gap, vol, theta):
        return -1.0
    vax, vay, vaz = velocities[a, 0], velocities[a, 1], velocities[a, 2]
    vbx, vby, vbz = velocities[b, 0], velocities[b, 1], velocities[b, 2]
    dot = vax * vbx + vay * vby + vaz * vbz
    norms = math.sqrt((vax * vax + vay * vay + vaz * vaz) * (vbx * vbx + vby * vby + vbz * vbz))
    if not ((norms == 0.0) | (dot >= cos_max * norms)):
        return -1.0
    if not force_needed:
        return np.nan
    f = force(ra, rb, gap, gamma, theta, cos_theta, sin_theta, vol)
    return f if f > min_force else -1.0


@njit(inline="always", error_model="numpy")
def _scan(volume, within_rupture, force, id1, id2, id_offset, velocities, radii, content,
          delta, gamma, theta, cos_max, min_force, force_needed, out_i, out_j, out_f, out_k):
    """The loop over the contacts shared by :func:`bond_kernel` and :func:`bond_components`:
    bond test of each contact, bonded pairs to ``out_*`` (``out_k``: the contact's row in
    the dump, whose overlap the rupture-work weight needs). Returns the bond count, or
    -1 - k when contact k refers to a row outside the frame.

    The model's functions are arguments of their own numba type, so each liquid model gets
    its own loop with its law inlined (with the model as a run-time value inside the loop
    the whole pass was measured 3.5x slower).
    """
    n = len(radii)
    cos_theta, sin_theta = math.cos(theta), math.sin(theta)
    count = 0
    for k in range(len(id1)):
        a = np.int64(id1[k]) - id_offset
        b = np.int64(id2[k]) - id_offset
        if a < 0 or a >= n or b < 0 or b >= n:
            return -1 - k
        f = _bond(a, b, -delta[k], velocities, radii, content, volume, within_rupture, force,
                  gamma, theta, cos_theta, sin_theta, cos_max, min_force, force_needed)
        if f < 0.0:                               # not a bond (NaN: a bond, force not needed)
            continue
        out_i[count] = a
        out_j[count] = b
        out_f[count] = f
        out_k[count] = k
        count += 1
    return count


# _bond_kernel, _bond_components and _rupture_work are never compiled as written: their
# globals VOLUME, WITHIN_RUPTURE and FORCE exist only in the copies _for_law compiles per law.
def _bond_kernel(id1, id2, id_offset, velocities, radii, content, delta, gamma, theta,
                 cos_max, min_force):
    """:func:`bond_kernel` for the law bound to ``VOLUME``, ``WITHIN_RUPTURE``, ``FORCE``
    (compiled per law by :func:`_for_law`)."""
    m = len(id1)
    out_i = np.empty(m, np.int64)
    out_j = np.empty(m, np.int64)
    out_f = np.empty(m, np.float64)
    out_k = np.empty(m, np.int64)
    count = _scan(VOLUME, WITHIN_RUPTURE, FORCE, id1, id2, id_offset, velocities, radii,
                  content, delta, gamma, theta, cos_max, min_force, True, out_i, out_j, out_f,
                  out_k)
    return count, out_i, out_j, out_f, out_k


def bond_kernel(id1, id2, id_offset, velocities, radii, content, delta, volume,
                within_rupture, force, gamma, theta, cos_max, min_force):
    """One pass over the contacts: the bond test of :func:`_bond` for each.

    Particle rows are ``id1 - id_offset`` and ``id2 - id_offset`` (the ids themselves when
    the caller already mapped them, with offset 0). ``content``: liquid content per
    particle (fraction of its volume). ``volume``, ``within_rupture``, ``force``: the
    model's law (:func:`law`). Returns
    (count, i, j, force, contact row) with the bonded pairs in the first ``count`` entries,
    or count = -1 - k when contact k refers to a row outside the frame.
    """
    return _for_law(_bond_kernel, VOLUME=volume, WITHIN_RUPTURE=within_rupture, FORCE=force)(
        id1, id2, id_offset, velocities, radii, content, delta, gamma, theta, cos_max,
        min_force)


def bond_components(id1, id2, id_offset, velocities, radii, content, delta, volume,
                    within_rupture, force, gamma, theta, cos_max, min_force, force_needed, y,
                    length):
    """Bond test, granules and unwrapping along the periodic axis in one compiled call:
    one pass over the contacts, one over the bonds, one over the particles.

    Each bonded contact is merged into a union-find forest whose nodes also carry
    their periodic image count relative to their parent (``u = y + length * image``
    unwrapped); a bond between two particles of one tree whose image counts disagree with
    the minimum-image displacement closes a cycle around the periodic axis: that granule
    *percolates* (its extent along the axis is the whole box) and, having no unwrapped
    layout, keeps its members' positions in the box. Roots are always the
    smallest row of their tree, so granule k is numbered in order of its first member and
    its unwrapped coordinates are laid out from that member, as the breadth-first reference
    (:func:`ligwf.analysis.granules.bonds.unwrap_reference`) lays them out; for a granule that does not
    percolate every path gives the same image counts, so both agree to rounding.

    ``length`` <= 0: no periodic axis (image counts stay 0). Returns (count, i, j, force,
    labels, y unwrapped, percolating per granule, granule count); count = -1 - k when
    contact k refers to a row outside the frame.
    """
    return _for_law(_bond_components, VOLUME=volume, WITHIN_RUPTURE=within_rupture,
                    FORCE=force)(
        id1, id2, id_offset, velocities, radii, content, delta, gamma, theta, cos_max,
        min_force, force_needed, y, length)


def _bond_components(id1, id2, id_offset, velocities, radii, content, delta, gamma, theta,
                     cos_max, min_force, force_needed, y, length):
    """:func:`bond_components` for the law bound to ``VOLUME``, ``WITHIN_RUPTURE``,
    ``FORCE`` (compiled per law by :func:`_for_law`)."""
    m = len(id1)
    n = len(radii)
    out_i = np.empty(m, np.int64)
    out_j = np.empty(m, np.int64)
    out_f = np.empty(m, np.float64)
    count = _scan(VOLUME, WITHIN_RUPTURE, FORCE, id1, id2, id_offset, velocities, radii,
                  content, delta, gamma, theta, cos_max, min_force, force_needed, out_i, out_j,
                  out_f, np.empty(m, np.int64))
    if count < 0:
        return (count, out_i, out_j, out_f, np.arange(n), y, np.zeros(n, np.bool_), 0)
    labels, unwrapped, percolating, n_granules = components_images(n, out_i, out_j, count, y,
                                                                    length)
    return count, out_i, out_j, out_f, labels, unwrapped, percolating, n_granules


@cached_jit(error_model="numpy")
def components_images(n, i, j, count, y, length):
    """Connected components of the first ``count`` pairs (i, j) of n particles with their
    unwrapping along the periodic axis and percolation test (the union-find pass of
    :func:`bond_components`, also used on the intra-community bonds of
    :mod:`ligwf.analysis.granules.definitions`). Returns (labels, y unwrapped, percolating per
    granule, granule count); labels canonical (numbered in order of first member).

    Each pair is merged into a union-find forest whose nodes also carry their periodic
    image count relative to their parent (``u = y + length * image`` unwrapped); a pair
    between two particles of one tree whose image counts disagree with the minimum-image
    displacement closes a cycle around the periodic axis: that granule *percolates*.
    """
    out_i, out_j = i, j
    parent = np.arange(n)
    image = np.zeros(n, np.int64)
    winds = np.zeros(n, np.bool_)                 # per root: its tree closes a periodic cycle
    # union-find over the bonds, written out in the loop: as helper calls taking the arrays
    # the same loop was measured 3.3x slower. Finds use path halving (each node on the
    # way is re-pointed at its grandparent, its image count updated to match).
    periodic = length > 0.0
    for k in range(count):
        a, b = out_i[k], out_j[k]
        # minimum image: u_b - u_a = (y_b - y_a) - length * shift
        shift = np.int64(np.rint((y[b] - y[a]) / length)) if periodic else np.int64(0)
        ra, ma = a, np.int64(0)
        while parent[ra] != ra:
            p = parent[ra]
            gp = parent[p]
            if gp != p:
                image[ra] += image[p]
                parent[ra] = gp
            ma += image[ra]
            ra = parent[ra]
        rb, mb = b, np.int64(0)
        while parent[rb] != rb:
            p = parent[rb]
            gp = parent[p]
            if gp != p:
                image[rb] += image[p]
                parent[rb] = gp
            mb += image[rb]
            rb = parent[rb]
        if ra == rb:                              # a cycle: does it wind around the axis?
            if mb != ma - shift:
                winds[ra] = True
        elif ra < rb:                             # the smaller row stays the root
            parent[rb] = ra
            image[rb] = ma - shift - mb
            winds[ra] |= winds[rb]
        else:
            parent[ra] = rb
            image[ra] = mb + shift - ma
            winds[rb] |= winds[ra]
    # every parent is a smaller row than its child (roots are their tree's smallest row, path
    # halving points at a grandparent): in row order, a node's parent is already resolved to
    # its root with its final image count, so each node takes one step instead of a search
    labels = np.empty(n, np.int64)
    unwrapped = np.empty(n, np.float64)
    percolating = np.zeros(n, np.bool_)
    n_granules = 0
    for x in range(n):
        p = parent[x]
        if p == x:                                # the first member of a new granule
            labels[x] = n_granules
            percolating[n_granules] = winds[x]
            n_granules += 1
            unwrapped[x] = y[x]
            continue
        image[x] += image[p]                      # a root's own image count is 0
        r = parent[p]
        parent[x] = r
        labels[x] = labels[r]
        # a percolating granule has no unwrapped layout: its members stay in the box
        unwrapped[x] = y[x] if (image[x] == 0 or winds[r]) else y[x] + length * image[x]
    return labels, unwrapped, percolating[:n_granules], n_granules


@cached_jit(inline="always")
def _find(parent, x):
    while parent[x] != x:
        parent[x] = parent[parent[x]]      # path halving
        x = parent[x]
    return x


@cached_jit()
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


@cached_jit(error_model="numpy")
def granule_sums(labels, n_granules, radii, positions, axis, axis_values):
    """Members, volume (m^3), volume-weighted position sums (m^4) and first member (row)
    per granule, in one pass (the same sums, in the same order, as numpy.bincount).
    ``axis`` >= 0: coordinate ``axis`` is taken from ``axis_values`` (unwrapped) instead."""
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
        for d in range(3):
            moment[g, d] += v * (axis_values[x] if d == axis else positions[x, d])
    return members, volume, moment, first


def _rupture_work(r_i, r_j, lo, hi, vol, gamma, theta, nodes, weights):
    """:func:`rupture_work` for the law bound to ``FORCE`` (compiled per law by
    :func:`_for_law`). Touching pairs (``lo`` = 0) of equal radii and volume do the same
    arithmetic: done once per bit pattern (:mod:`ligwf.analysis.pair_table_numba`)."""
    cos_theta, sin_theta = math.cos(theta), math.sin(theta)
    out = np.empty(len(r_i), np.float64)
    bits = (r_i.view(np.int64), r_j.view(np.int64), hi.view(np.int64), vol.view(np.int64))
    table = new_table()
    for k in range(len(r_i)):
        slot = find_slot(table, bits, k) if lo[k] == 0.0 else -1
        if slot >= 0 and table[2][slot]:
            out[k] = table[1][slot]
            continue
        half, mid = 0.5 * (hi[k] - lo[k]), 0.5 * (hi[k] + lo[k])
        total = 0.0
        for q in range(len(nodes)):
            total += weights[q] * FORCE(r_i[k], r_j[k], mid + half * nodes[q], gamma, theta,
                                        cos_theta, sin_theta, vol[k])
        out[k] = half * total
        if slot >= 0:
            remember(table, bits, k, slot, out[k])
    return out


def rupture_work(r_i, r_j, lo, hi, vol, force, gamma, theta, nodes, weights):
    """Work, J, the bridge of each pair still does between gap ``lo`` and its rupture gap
    ``hi`` (m): Gauss-Legendre quadrature of the model's numba ``force`` at ``nodes`` /
    ``weights`` on [-1, 1] (the same nodes as the numpy reference,
    :func:`ligwf.analysis.granules.bridge_law.relative_energy`)."""
    return _for_law(_rupture_work, FORCE=force)(r_i, r_j, lo, hi, vol, gamma, theta, nodes,
                                                weights)


_COMPILED: dict[tuple, Callable] = {}


def _for_law(kernel, **law) -> Callable:
    """``kernel`` compiled with the law's numba functions ``law`` bound to its global names
    (``VOLUME``, ``WITHIN_RUPTURE``, ``FORCE``): built once per process and law, compiled
    once per installation (:func:`ligwf.numba_cache.specialised`)."""
    key = (kernel, *law.items())
    compiled = _COMPILED.get(key)
    if compiled is None:
        force = getattr(law["FORCE"], "py_func", law["FORCE"])
        model = force.__module__.rsplit(".", 1)[-1]          # readable cache file names
        compiled = specialised(kernel, f"{model}_{law_digest(*law.values())}",
                               {"error_model": "numpy"}, **law)
        _COMPILED[key] = compiled
    return compiled


def warm_up(models: tuple[str, ...] | None = None) -> None:
    """Compile (or load from the cache) every kernel on a two-particle frame, the bond
    kernels for each of ``models`` (default: every registered wet model)."""
    v = np.ones((2, 3))
    r, c = np.full(2, 1e-3), np.full(2, 0.02)
    names = models if models is not None else [n for n in liquids.names() if liquids.get(n).wet]
    for name in names:
        fns = law(liquids.get(name))
        bond_kernel(np.array([1]), np.array([2]), 1, v, r, c, np.array([1e-6]), *fns,
                    0.02, 0.1, 0.5, 0.0)
        bond_components(np.array([1]), np.array([2]), 1, v, r, c, np.array([1e-6]),
                        *fns, 0.02, 0.1, 0.5, 0.0, True, v[:, 1].copy(), 1.0)
        rupture_work(r, r, np.zeros(2), np.full(2, 1e-6), np.full(2, 1e-12), fns[2], 0.02,
                     0.1, np.zeros(1), np.full(1, 2.0))
    i, j = np.array([0]), np.array([1])
    from ligwf.analysis.cpm_numba import cpm_quality_compiled, louvain_cpm

    cpm = louvain_cpm(2, i, j, np.ones(1), np.ones(2), 0.1, 0)
    cpm_quality_compiled(cpm, i, j, np.ones(1), np.ones(2), 0.1)
    labels = union_find_labels(2, i, j)
    components_images(2, i, j, 1, v[:, 1].copy(), 1.0)
    for axis in (-1, 1):
        granule_sums(labels, 1, r, v, axis, v[:, 1].copy())
