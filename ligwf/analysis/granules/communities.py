"""Granules as communities of the bonded graph: CPM (the default granule definition, see
:mod:`ligwf.analysis.granules.definitions`; compiled Louvain, its plain-Python reference giving the
same partition, igraph's Leiden and leidenalg as independent optimisers compared by
quality) and modularity Louvain (an extra label), canonical labels.

An alternative to the connected components of :mod:`ligwf.analysis.granules.bonds` (which
over-merge a dense wet bed into one cluster), stored next to them on request
(``ligwf analyse --louvain``).
"""

from __future__ import annotations

import numpy as np


def _is_canonical(labels: np.ndarray) -> bool:
    """True when label k first appears after labels 0..k-1 (then the running maximum
    never jumps by more than one), checked in one pass instead of a sort."""
    if len(labels) == 0:
        return True
    return labels[0] == 0 and bool(np.all(np.diff(np.maximum.accumulate(labels)) <= 1))


def canonical_labels(labels: np.ndarray) -> np.ndarray:
    """Relabel so granule k is the k-th distinct label met in particle (id) order."""
    if _is_canonical(labels):      # often numbered in this order already
        return labels.astype(np.int64, copy=False)
    _, first, inverse = np.unique(labels, return_index=True, return_inverse=True)
    rank = np.empty(len(first), dtype=np.int64)
    rank[np.argsort(first, kind="stable")] = np.arange(len(first))
    return rank[inverse.reshape(-1)]


def louvain_labels(n: int, i: np.ndarray, j: np.ndarray, force: np.ndarray,
                   seed: int = 0, resolution: float = 1.0) -> np.ndarray:
    """Alternative granules: Louvain communities of the bridge-force-weighted bonded graph.

    Connected components over-merge in a dense wet bed (one cluster holds ~ the whole bed),
    whereas communities split it where bridges are weak relative to the rest. Weights are
    forces normalised by their mean (N / N), so the result does not depend on the CG rule's
    force scale. Labels are canonical like
    :func:`ligwf.analysis.granules.bonds.label_fast`; singletons stay singletons.
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
    return canonical_labels(labels)


def cpm_quality(labels: np.ndarray, i: np.ndarray, j: np.ndarray, weight: np.ndarray,
                node_weight: np.ndarray, resolution: float) -> float:
    """CPM quality of a partition, computed in numpy: sum over communities c of
    (edge weight inside c) - resolution * (node weight of c)^2 / 2.

    The independent check of both Leiden implementations (igraph reports
    (2 W_in - resolution sum N_c^2) / (2 W), leidenalg 2 (W_in - resolution sum N_c (N_c - 1) / 2);
    all three differ only by constants of the graph, so they rank partitions alike).
    """
    inside = labels[i] == labels[j]
    sizes = np.bincount(labels, weights=node_weight)
    return float(weight[inside].sum() - resolution * 0.5 * (sizes * sizes).sum())


def cpm_labels(n: int, i: np.ndarray, j: np.ndarray, weight: np.ndarray,
               node_weight: np.ndarray, resolution: float, seed: int = 0,
               with_quality: bool = False):
    """Communities maximising the constant Potts model: compiled Louvain with two
    iterations (:func:`ligwf.analysis.cpm_numba.louvain_cpm`), canonical labels. A frame's
    partition depends only on the frame and the seed (identical in serial and MPI runs).

    Why not igraph's Leiden (:func:`cpm_labels_leiden`): at 360k
    particles it took ~5 s per frame on one core; on real CG1-CG3 bond graphs the
    compiled Louvain ends within 1 % of the total edge weight of Leiden's CPM quality
    (mean 0.3 %, sometimes above it) at 3x-10x the speed. ``with_quality``: also return
    the quality the compiled code computes of its partition (the tests check it against
    numpy's :func:`cpm_quality` to 1e-6).
    """
    from ligwf.analysis.cpm_numba import cpm_quality_compiled, louvain_cpm

    if n == 0:
        return (np.zeros(0, np.int64), 0.0) if with_quality else np.zeros(0, np.int64)
    i64, j64 = np.asarray(i, np.int64), np.asarray(j, np.int64)
    w, nw = np.asarray(weight, np.float64), np.asarray(node_weight, np.float64)
    labels = canonical_labels(louvain_cpm(int(n), i64, j64, w, nw, float(resolution), int(seed)))
    if with_quality:
        return labels, float(cpm_quality_compiled(labels, i64, j64, w, nw, float(resolution)))
    return labels


def _moves_reference(adj, node_w, resolution, order, max_passes, init):
    """Plain-Python local moving of :func:`ligwf.analysis.cpm_numba._local_moving` (dicts
    and lists, the same visiting order, sums and tie rule)."""
    n = len(node_w)
    comm = [int(c) for c in init]
    comm_w = [0.0] * n
    for v in range(n):
        comm_w[comm[v]] += node_w[v]
    used = set(comm)
    free = [c for c in range(n - 1, -1, -1) if c not in used]      # a stack, top = last
    moves = 0
    for _ in range(max_passes):
        moved = 0
        for v in order:
            cv, nv = comm[v], node_w[v]
            acc: dict[int, float] = {}
            for u, x in adj[v]:
                acc[comm[u]] = acc.get(comm[u], 0.0) + x
            comm_w[cv] -= nv
            best, best_gain = cv, acc.get(cv, 0.0) - resolution * nv * comm_w[cv]
            for c, a in acc.items():                # insertion order = first touch
                if c == cv:
                    continue
                gain = a - resolution * nv * comm_w[c]
                if gain > best_gain + 1e-12 * (abs(best_gain) + abs(gain)):
                    best, best_gain = c, gain
            if best_gain < 0.0 and comm_w[cv] > 0.0:
                best = free.pop()
            elif best_gain < 0.0:
                best = cv
            if best != cv and comm_w[cv] == 0.0:
                free.append(cv)
            comm_w[best] += nv
            if best != cv:
                comm[v] = best
                moved += 1
        moves += moved
        if moved == 0:
            break
    return comm, moves


def _first_appearance(comm):
    """Labels numbered 0..K-1 in order of first appearance."""
    new: dict[int, int] = {}
    return [new.setdefault(c, len(new)) for c in comm]


def louvain_cpm_reference(n, i, j, w, node_w, resolution, seed, iterations=2, max_passes=50,
                          max_levels=20) -> np.ndarray:
    """The reference of the compiled Louvain (:func:`ligwf.analysis.cpm_numba.louvain_cpm`):
    the same algorithm written again in plain Python (adjacency lists in edge order, dict
    sums, stable sorted aggregation), drawing the same node orders
    (:func:`~ligwf.analysis.cpm_numba.level_order`): the same partition for a seed."""
    from ligwf.analysis.cpm_numba import level_order, seed_orders

    seed_orders(int(seed))
    edges = [(int(a), int(b), float(x)) for a, b, x in zip(i, j, w)]
    weights0 = [float(x) for x in node_w]
    labels = list(range(n))
    for _ in range(iterations):
        out = list(range(n))
        ed, nw, size, init = edges, weights0, n, labels
        for level_no in range(max_levels):
            adj: list[list[tuple[int, float]]] = [[] for _ in range(size)]
            for a, b, x in ed:
                if a != b:
                    adj[a].append((b, x))
                    adj[b].append((a, x))
            order = level_order(size, level_no).tolist()
            comm, moves = _moves_reference(adj, nw, resolution, order, max_passes, init)
            level = _first_appearance(comm)
            k = max(level) + 1 if level else 0
            out = [level[c] for c in out]
            if moves == 0 or k == size:
                break
            agg_w = [0.0] * k
            for v in range(size):
                agg_w[level[v]] += nw[v]
            pairs = []
            for v in range(size):              # each undirected edge once (u > v), CSR order
                for u, x in adj[v]:
                    if u > v and level[u] != level[v]:
                        a, b = sorted((level[v], level[u]))
                        pairs.append((a * k + b, x))
            pairs.sort(key=lambda t: t[0])      # stable, as the compiled mergesort
            ed = []
            for key, x in pairs:
                if ed and ed[-1][0] == key // k and ed[-1][1] == key % k:
                    ed[-1] = (ed[-1][0], ed[-1][1], ed[-1][2] + x)
                else:
                    ed.append((key // k, key % k, x))
            nw, size, init = agg_w, k, list(range(k))
        labels = _first_appearance(out)
    return np.asarray(labels, dtype=np.int64)


def cpm_labels_reference(n: int, i: np.ndarray, j: np.ndarray, weight: np.ndarray,
                         node_weight: np.ndarray, resolution: float, seed: int = 0) -> np.ndarray:
    """The reference of :func:`cpm_labels`: the same Louvain in plain Python
    (:func:`louvain_cpm_reference`), canonical labels: the same partition for a seed."""
    if n == 0:
        return np.zeros(0, np.int64)
    return canonical_labels(louvain_cpm_reference(
        int(n), np.asarray(i), np.asarray(j), np.asarray(weight, float),
        np.asarray(node_weight, float), float(resolution), int(seed)))


def cpm_labels_leiden(n: int, i: np.ndarray, j: np.ndarray, weight: np.ndarray,
                      node_weight: np.ndarray, resolution: float, seed: int = 0) -> np.ndarray:
    """A second, independent CPM optimiser: igraph's compiled Leiden (2 iterations), with a
    refinement step Louvain lacks, canonical labels. The two reach different local optima;
    they are compared by their CPM quality.

    The graph is built from a list of (int, int) tuples: igraph 1.0 reads a numpy edge
    array element by element, 2.2x slower (1.56 vs 0.70 s for 1.2M edges). igraph draws
    from a process-wide generator: it is set to a ``random.Random(seed)`` per call."""
    import random

    import igraph as ig

    if n == 0:
        return np.zeros(0, np.int64)
    ig.set_random_number_generator(random.Random(seed))
    graph = ig.Graph(n=n, edges=list(zip(np.asarray(i).tolist(), np.asarray(j).tolist())))
    part = graph.community_leiden(objective_function="CPM", weights=np.asarray(weight).tolist(),
                                  node_weights=np.asarray(node_weight).tolist(),
                                  resolution=resolution, n_iterations=2)
    return canonical_labels(np.asarray(part.membership, dtype=np.int64))


def cpm_labels_leidenalg(n: int, i: np.ndarray, j: np.ndarray, weight: np.ndarray,
                         node_weight: np.ndarray, resolution: float, seed: int = 0) -> np.ndarray:
    """A third CPM optimiser: leidenalg's own Leiden implementation
    (``CPMVertexPartition``, iterated to convergence; ~13x slower than igraph's). The two algorithms
    differ in their moves and, on real bond graphs, reach different local optima (CPM
    quality within ~0.5 % of the total edge weight, either one higher, on the CG3 test
    dumps); the exact check of the fast path is its own reported quality against
    :func:`cpm_quality` (1e-6)."""
    import igraph as ig
    import leidenalg

    if n == 0:
        return np.zeros(0, np.int64)
    graph = ig.Graph(n=n, edges=list(zip(i.tolist(), j.tolist())))
    sizes = node_weight.tolist()
    if np.all(node_weight == node_weight[0]):
        # leidenalg takes integer node sizes: equal weights w become 1 with resolution w^2,
        # the same objective (every community term scales by w^2)
        sizes, resolution = [1] * n, resolution * float(node_weight[0]) ** 2
    part = leidenalg.find_partition(graph, leidenalg.CPMVertexPartition,
                                    weights=weight.tolist(), node_sizes=sizes,
                                    resolution_parameter=resolution, n_iterations=-1, seed=seed)
    return canonical_labels(np.asarray(part.membership, dtype=np.int64))
