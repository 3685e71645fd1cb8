"""Granules as communities: Louvain communities of the bonded graph, canonical labels.

An alternative to the connected components of :mod:`ligwf.analysis.granules` (which
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
    :func:`ligwf.analysis.granules.label_fast`; singletons stay singletons.
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
