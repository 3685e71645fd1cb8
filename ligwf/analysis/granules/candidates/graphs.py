"""Bond graphs of a frame cut into granules: connected components with the percolation test
along the periodic axis (a union-find carrying each node's offset along the axis), and
communities (networkx Louvain; igraph Leiden with the modularity or constant Potts
objective), a community percolating when its own bonds close a cycle around the axis."""

from __future__ import annotations

import random

import numpy as np

from ligwf.numba_cache import cached_jit


@cached_jit()
def _find(parent, off, x):
    # returns root and the offset of x relative to the root (with path compression)
    root = x
    acc = 0.0
    while parent[root] != root:
        acc += off[root]
        root = parent[root]
    # compress
    cur = x
    curacc = acc
    while parent[cur] != cur:
        nxt = parent[cur]
        o = off[cur]
        parent[cur] = root
        off[cur] = curacc
        curacc -= o
        cur = nxt
    return root, acc



@cached_jit()
def uf_percolation(n, i, j, dy, length):
    """Union-find with offsets along the periodic axis: labels (root per node) and, per
    root, whether the component closes a cycle around the axis."""
    parent = np.arange(n)
    off = np.zeros(n)
    perc = np.zeros(n, dtype=np.bool_)
    for e in range(len(i)):
        ri, oi = _find(parent, off, i[e])
        rj, oj = _find(parent, off, j[e])
        if ri == rj:
            if abs(oi + dy[e] - oj) > 0.5 * length:
                perc[ri] = True
        else:
            parent[rj] = ri
            off[rj] = oi + dy[e] - oj
            if perc[rj]:
                perc[ri] = True
    labels = np.empty(n, dtype=np.int64)
    for x in range(n):
        r, _ = _find(parent, off, x)
        labels[x] = r
    return labels, perc


def components(n, i, j, dy, length):
    labels, perc = uf_percolation(n, i.astype(np.int64), j.astype(np.int64), dy, length)
    return labels, perc[labels]          # percolation flag per particle


def community_percolation(labels, i, j, dy, length, n):
    """Per particle: does its community's induced subgraph wrap the periodic axis?"""
    same = labels[i] == labels[j]
    _, pp = components(n, i[same], j[same], dy[same], length)
    flag = np.zeros(labels.max() + 1, bool)
    np.logical_or.at(flag, labels, pp)
    return flag[labels]


def louvain(n, i, j, w, seed=0, resolution=1.0):
    import networkx as nx
    g = nx.Graph()
    g.add_nodes_from(range(n))
    g.add_weighted_edges_from(zip(i.tolist(), j.tolist(), (w / w.mean()).tolist()))
    labels = np.empty(n, dtype=np.int64)
    for k, m in enumerate(nx.community.louvain_communities(g, weight="weight",
                                                           resolution=resolution, seed=seed)):
        labels[list(m)] = k
    return labels


def leiden(n, i, j, w, objective, resolution, node_weights=None, seed=0):
    import igraph as ig
    random.seed(seed)
    ig.set_random_number_generator(random)
    g = ig.Graph(n=n, edges=np.stack([i, j], axis=1).tolist())
    kw = {}
    if node_weights is not None:
        kw["node_weights"] = node_weights.tolist()
    part = g.community_leiden(objective_function=objective, weights=w.tolist(),
                              resolution=resolution, n_iterations=-1, **kw)   # to convergence, as ligwf
    return np.asarray(part.membership, dtype=np.int64)

