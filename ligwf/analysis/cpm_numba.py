"""Constant Potts model communities by compiled Louvain (numba): the fast path of the
default granule definition.

CPM quality of a partition: Q = sum over communities c of W_in(c) - resolution N_c^2 / 2, with
W_in the edge weight inside c and N_c its node weight (:func:`ligwf.analysis.granules.communities.
cpm_quality` computes it in numpy). Louvain (Blondel et al. 2008) with the CPM gain:

1. *local moving*: nodes in order (on the particle graph: id order from a seeded start,
   for cache locality; on aggregated graphs: a seeded random order); each leaves its
   community and joins the neighbouring community c with the largest gain
   w(v, c) - resolution n_v N_c (or a community of its own, gain 0); passes repeat until
   no node moves;
2. *aggregation*: each community becomes a node (weight N_c, edges summed), and 1. runs
   on that graph; until a level moves nothing.

Louvain can leave a community internally disconnected (Leiden's refinement prevents
that); the granule definition takes the connected components of the bonds inside each
community anyway (:mod:`ligwf.analysis.granules.definitions`), so a disconnected community
becomes several granules. Why not igraph's compiled Leiden: at 360k particles its
partition took ~5 s per frame on one core, an order of magnitude too slow for the issue's
0.5 frames/s; this Louvain reaches CPM qualities within ~1 % of it (the tests compare them
on real engine dumps, in units of the total edge weight).
"""

from __future__ import annotations

import numpy as np

from ligwf.numba_cache import cached_jit

@cached_jit()
def _csr(n, i, j, w):
    """Symmetric CSR adjacency (indptr, indices, weights) of undirected edges (i, j, w);
    self-loops dropped (they add the same constant to every partition's quality)."""
    deg = np.zeros(n + 1, np.int64)
    for e in range(len(i)):
        if i[e] != j[e]:
            deg[i[e] + 1] += 1
            deg[j[e] + 1] += 1
    indptr = np.cumsum(deg)
    fill = indptr[:-1].copy()
    indices = np.empty(indptr[-1], np.int64)
    weights = np.empty(indptr[-1], np.float64)
    for e in range(len(i)):
        a, b = i[e], j[e]
        if a == b:
            continue
        indices[fill[a]] = b
        weights[fill[a]] = w[e]
        fill[a] += 1
        indices[fill[b]] = a
        weights[fill[b]] = w[e]
        fill[b] += 1
    return indptr, indices, weights


#: relative slack of the stay-proof of :func:`_local_moving` (floating-point rounding of
#: the gains is ~1e-16 relative; the proof demands a margin 1e7 times larger)
PROOF_SLACK = 1e-9


@cached_jit()
def _local_moving(indptr, indices, weights, node_w, resolution, order, max_passes, init):
    """Louvain local moving from the partition ``init`` (ids < n); returns (community per
    node, moves made). A node moves only for a strictly larger gain (relative tolerance
    1e-12), so every move raises the quality and the passes end.

    Nodes whose stay is proven are not re-evaluated (the same partition, bit for bit, as
    evaluating every node; 10 of the 12 passes of a 360k-particle frame move < 10 % of the
    nodes): a node that stayed at its last visit by a margin M (its stay gain over the best
    alternative, and over being alone) stays again while none of its neighbours moved (so
    its sums ``acc`` are bit-identical) and the weights of its own and its neighbours'
    communities changed in total by less than (M - slack) / (resolution n_v): each gain moves
    by resolution n_v times its community's weight change. ``drift`` is that total per community
    (it only grows), summed at the visit over the communities the node touches; the node's
    own community weight is still taken out and put back, as the full visit does, so every
    floating-point sum stays the same."""
    n = len(node_w)
    comm = init.copy()
    comm_w = np.zeros(n, np.float64)
    for v in range(n):
        comm_w[comm[v]] += node_w[v]
    total_w = 0.0
    for v in range(n):
        total_w += node_w[v]
    acc = np.zeros(n, np.float64)          # weight from the node to each community
    stamp = np.full(n, -1, np.int64)       # acc[c] is valid when stamp[c] == this visit
    visit = 0
    touched = np.empty(n, np.int64)
    free = np.empty(n, np.int64)           # stack of empty community ids
    n_free = 0
    used = np.zeros(n, np.bool_)
    for v in range(n):
        used[comm[v]] = True
    for c in range(n - 1, -1, -1):
        if not used[c]:
            free[n_free] = c
            n_free += 1
    # the stay-proof: per community its total weight change; per node its margin at the
    # last visit (< 0: not proven), the drift sum then, whether it was alone, the
    # communities it touched (CSR slots), whether a neighbour moved since
    drift = np.zeros(n, np.float64)
    margin = np.full(n, -1.0, np.float64)
    drift_at = np.zeros(n, np.float64)
    was_alone = np.zeros(n, np.bool_)
    seen = np.empty(indptr[n], np.int64)
    n_seen = np.zeros(n, np.int64)
    dirty = np.ones(n, np.bool_)
    singletons = True                      # from singletons the first pass moves most
    for v in range(n):                     # nodes: no proofs in it
        if init[v] != v:
            singletons = False
            break
    total_moves = 0
    for pass_no in range(max_passes):
        moved = 0
        prove = pass_no > 0 or not singletons
        for idx in range(n):
            v = order[idx]
            cv = comm[v]
            nv = node_w[v]
            if not dirty[v] and margin[v] >= 0.0:
                comm_w[cv] -= nv
                alone = comm_w[cv] == 0.0
                now = drift[cv]
                for t in range(indptr[v], indptr[v] + n_seen[v]):
                    now += drift[seen[t]]
                comm_w[cv] += nv
                if alone == was_alone[v] and resolution * nv * (now - drift_at[v]) < margin[v]:
                    continue               # proven: the full visit would stay too
            visit += 1                     # (not v: a node's next visit must not reuse
            k = 0                          # the sums of its previous one)
            spread = 0.0
            for e in range(indptr[v], indptr[v + 1]):
                c = comm[indices[e]]
                if stamp[c] != visit:
                    stamp[c] = visit
                    acc[c] = 0.0
                    touched[k] = c
                    k += 1
                acc[c] += weights[e]
                spread += abs(weights[e])
            comm_w[cv] -= nv
            stay = (acc[cv] if stamp[cv] == visit else 0.0) - resolution * nv * comm_w[cv]
            best, best_gain = cv, stay
            rival = -np.inf                # the best alternative's gain
            for t in range(k):
                c = touched[t]
                if c == cv:
                    continue
                gain = acc[c] - resolution * nv * comm_w[c]
                if gain > rival:
                    rival = gain
                if gain > best_gain + 1e-12 * (abs(best_gain) + abs(gain)):
                    best, best_gain = c, gain
            alone = comm_w[cv] == 0.0
            if best_gain < 0.0 and comm_w[cv] > 0.0:
                # alone (gain 0) beats every community: an empty id (one exists: cv still
                # holds another node, so at most n - 1 ids are in use)
                n_free -= 1
                best = free[n_free]
            elif best_gain < 0.0:
                best = cv                  # cv is empty now: staying is being alone
            if best != cv and comm_w[cv] == 0.0:
                free[n_free] = cv
                n_free += 1
            comm_w[best] += nv
            if best != cv:
                comm[v] = best
                moved += 1
            if not prove:
                continue
            dirty[v] = False
            if best != cv:
                drift[cv] += nv
                drift[best] += nv
                margin[v] = -1.0
                for e in range(indptr[v], indptr[v + 1]):
                    dirty[indices[e]] = True
                continue
            # stayed: its margin over every rival (and over being alone, gain 0)
            m = stay - rival
            if not alone and stay < m:
                m = stay
            m -= PROOF_SLACK * (spread + resolution * nv * total_w)
            margin[v] = m
            was_alone[v] = alone
            now = drift[cv]
            n_seen[v] = k
            for t in range(k):
                seen[indptr[v] + t] = touched[t]
                now += drift[touched[t]]
            drift_at[v] = now
        total_moves += moved
        if moved == 0:
            break
    return comm, total_moves


@cached_jit()
def _renumber(comm):
    """Communities numbered 0..K-1 in order of first appearance; returns (labels, K)."""
    n = len(comm)
    new = np.full(n, -1, np.int64)
    out = np.empty(n, np.int64)
    k = 0
    for v in range(n):
        c = comm[v]
        if new[c] < 0:
            new[c] = k
            k += 1
        out[v] = new[c]
    return out, k


@cached_jit()
def _stable_key_order(keys, k):
    """The permutation that sorts pair keys a k + b (0 <= a, b < k) stably: the order of
    ``numpy.argsort(keys, kind="mergesort")``, by two stable counting passes (by b, then
    by a: linear in the number of keys instead of m log m)."""
    m = len(keys)
    count = np.zeros(k + 1, np.int64)
    for t in range(m):
        count[keys[t] % k + 1] += 1
    for c in range(k):
        count[c + 1] += count[c]
    by_b = np.empty(m, np.int64)
    for t in range(m):
        b = keys[t] % k
        by_b[count[b]] = t
        count[b] += 1
    count[:] = 0
    for t in range(m):
        count[keys[t] // k + 1] += 1
    for c in range(k):
        count[c + 1] += count[c]
    order = np.empty(m, np.int64)
    for s in range(m):
        t = by_b[s]
        a = keys[t] // k
        order[count[a]] = t
        count[a] += 1
    return order


@cached_jit()
def _aggregate(indptr, indices, weights, node_w, labels, k):
    """The graph of communities: node weights summed, edges between communities summed
    (each undirected edge once), internal edges dropped. Returns (i, j, w, node_w)."""
    nw = np.zeros(k, np.float64)
    for v in range(len(labels)):
        nw[labels[v]] += node_w[v]
    m = 0
    for v in range(len(labels)):
        for e in range(indptr[v], indptr[v + 1]):
            u = indices[e]
            if u > v and labels[u] != labels[v]:
                m += 1
    keys = np.empty(m, np.int64)
    ws = np.empty(m, np.float64)
    m = 0
    for v in range(len(labels)):
        for e in range(indptr[v], indptr[v + 1]):
            u = indices[e]
            if u > v and labels[u] != labels[v]:
                a, b = labels[v], labels[u]
                if a > b:
                    a, b = b, a
                keys[m] = a * k + b
                ws[m] = weights[e]
                m += 1
    order = _stable_key_order(keys, k)
    out_i = np.empty(m, np.int64)
    out_j = np.empty(m, np.int64)
    out_w = np.empty(m, np.float64)
    q = -1
    last = -1
    for t in range(m):
        key = keys[order[t]]
        if key != last:
            q += 1
            out_i[q] = key // k
            out_j[q] = key % k
            out_w[q] = 0.0
            last = key
        out_w[q] += ws[order[t]]
    return out_i[:q + 1], out_j[:q + 1], out_w[:q + 1], nw


@cached_jit()
def seed_orders(seed):
    """Seed the generator of :func:`level_order` (numba's own, separate from numpy's)."""
    np.random.seed(seed)


@cached_jit()
def level_order(size, level_no):
    """Node order of one level's local moving. The particle graph (level 0) is visited in
    id order from a seeded start: neighbouring ids are mostly neighbouring particles, and a
    random order's cache misses made this level 8x slower at 360k particles (2.2 vs
    0.27 s; CPM quality 0.6 % higher). Aggregated levels: a seeded random permutation.
    The numpy reference of :mod:`ligwf.analysis.granules.communities` draws the same orders."""
    if level_no == 0:
        return (np.arange(size) + np.random.randint(0, size)) % size
    return np.random.permutation(size)


@cached_jit()
def _levels(n, graph, node_w, resolution, start, max_passes, max_levels):
    """One Louvain run: local moving on the graph (``graph``: its CSR, :func:`_csr`) from
    partition ``start``, then on the aggregated graphs from singletons, until a level
    moves nothing."""
    labels = np.arange(n)
    cnw = node_w
    size = n
    init = start.copy()
    indptr, indices, weights = graph
    ci, cj, cw = np.empty(0, np.int64), np.empty(0, np.int64), np.empty(0, np.float64)
    for level_no in range(max_levels):
        if level_no > 0:
            indptr, indices, weights = _csr(size, ci, cj, cw)
        order = level_order(size, level_no)
        comm, moves = _local_moving(indptr, indices, weights, cnw, resolution, order, max_passes,
                                    init)
        level, k = _renumber(comm)
        for v in range(n):
            labels[v] = level[labels[v]]
        if moves == 0 or k == size:
            break
        ci, cj, cw, cnw = _aggregate(indptr, indices, weights, cnw, level, k)
        size = k
        init = np.arange(size)
    return _renumber(labels)[0]


@cached_jit()
def louvain_cpm(n, i, j, w, node_w, resolution, seed, iterations=2, max_passes=50, max_levels=20):
    """Community per node (0..K-1 in order of first appearance) maximising CPM with
    resolution by Louvain; node orders drawn from ``seed``. ``iterations``: the
    first run starts from singletons, each further run from the previous partition (as
    igraph's Leiden iterations do), which on real bond graphs recovers most of the quality
    Louvain's first run leaves to Leiden."""
    seed_orders(seed)
    ci, cj = i.astype(np.int64), j.astype(np.int64)
    cw, cnw = w.astype(np.float64), node_w.astype(np.float64)
    labels = np.arange(n)
    graph = _csr(n, ci, cj, cw)            # the particle graph: built once for every run
    for _ in range(iterations):
        labels = _levels(n, graph, cnw, resolution, labels, max_passes, max_levels)
    return labels


@cached_jit()
def cpm_quality_compiled(labels, i, j, w, node_w, resolution):
    """CPM quality of a partition, sum of W_in(c) - resolution N_c^2 / 2, in one compiled loop
    (the value the fast path reports; the numpy version in ligwf.analysis.granules.communities is
    the independent check)."""
    k = 0
    for v in range(len(labels)):
        if labels[v] + 1 > k:
            k = labels[v] + 1
    size = np.zeros(k, np.float64)
    for v in range(len(labels)):
        size[labels[v]] += node_w[v]
    inside = 0.0
    for e in range(len(i)):
        if labels[i[e]] == labels[j[e]]:
            inside += w[e]
    penalty = 0.0
    for c in range(k):
        penalty += size[c] * size[c]
    return inside - resolution * 0.5 * penalty
