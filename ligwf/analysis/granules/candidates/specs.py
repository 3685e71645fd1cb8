"""The candidate granule definitions (:data:`CANDIDATES`) and their bonds and partitions on
a case's frames (:class:`Evaluator`): which bridges are bonds (a velocity angle in a frame,
a minimum relative force, persistence over k dumps), then how the bond graph is cut."""

from __future__ import annotations

import math
from dataclasses import dataclass, replace

import numpy as np

from ligwf.analysis.granules.candidates.frames import Case, Frame
from ligwf.analysis.granules.candidates.graphs import (community_percolation, components,
                                                       leiden, louvain)


@dataclass(frozen=True)
class Spec:
    name: str
    frame: str | None = None     # lab | rot | flow | None (no angle test)
    angle: float = 180.0         # deg
    f: float = 0.0               # minimum f_rel (0: every bridge)
    k: int = 1                   # persistence (dumps)
    part: str = "cc"             # cc | louvain | leiden | cpm
    gamma: float = 0.0           # CPM resolution
    weight: str = "force"        # CPM edge weight: force (f_rel) | energy (e_rel)

    def perturbations(self):
        """(parameter, spec) pairs with each threshold moved by -20 % and +20 %."""
        out = []
        for fac in (0.8, 1.2):
            if self.frame is not None:
                out.append((f"angle x{fac}", replace(self, angle=self.angle * fac)))
            if self.frame == "flow":
                out.append((f"flow radius x{fac}", replace(self, frame=f"flow@{3.0 * fac:g}")))
            if self.f > 0:
                out.append((f"f x{fac}", replace(self, f=self.f * fac)))
            if self.part == "cpm":
                out.append((f"gamma x{fac}", replace(self, gamma=self.gamma * fac)))
            if self.part in ("louvain", "leiden"):
                out.append((f"resolution x{fac}", replace(self, gamma=fac)))
        if self.k > 1:
            # +-20 % of k dumps rounded, at least one dump
            lo, hi = max(1, min(self.k - 1, round(0.8 * self.k))), max(self.k + 1, round(1.2 * self.k))
            out.append((f"k={lo}", replace(self, k=lo)))
            out.append((f"k={hi}", replace(self, k=hi)))
        return out


CANDIDATES = [
    Spec("cc lab 30", "lab", 30),
    Spec("cc lab 30 f0.5", "lab", 30, 0.5),
    Spec("cc lab 10", "lab", 10),
    Spec("cc rot 30", "rot", 30),
    Spec("cc rot 10", "rot", 10),
    Spec("cc rot 5", "rot", 5),
    Spec("cc rot 10 f0.5", "rot", 10, 0.5),
    Spec("cc flow 30", "flow", 30),
    Spec("cc flow 10", "flow", 10),
    Spec("cc flow 5", "flow", 5),
    Spec("cc flow 10 f0.5", "flow", 10, 0.5),
    Spec("cc persist k2 flow 10", "flow", 10, k=2),
    Spec("cc f0.5", None, 180, 0.5),
    Spec("cc f0.9", None, 180, 0.9),
    Spec("cc persist k2", k=2),
    Spec("cc persist k5", k=5),
    Spec("cc persist k10", k=10),
    Spec("cc persist k5 rot 10", "rot", 10, k=5),
    Spec("cc persist k5 flow 30", "flow", 30, k=5),
    Spec("louvain", part="louvain", gamma=1.0),
    Spec("leiden modularity", part="leiden", gamma=1.0),
    Spec("leiden cpm 0.05", part="cpm", gamma=0.05),
    Spec("leiden cpm 0.2", part="cpm", gamma=0.2),
    Spec("leiden cpm 0.02", part="cpm", gamma=0.02),
    Spec("leiden cpm 0.05 rot 30", "rot", 30, part="cpm", gamma=0.05),
    Spec("leiden cpm 0.02 rot 30", "rot", 30, part="cpm", gamma=0.02),
    Spec("leiden cpm 0.05 flow 30", "flow", 30, part="cpm", gamma=0.05),
    Spec("leiden cpm 0.05 persist k5", k=5, part="cpm", gamma=0.05),
    Spec("leiden cpm energy 0.001", part="cpm", gamma=0.001, weight="energy"),
    Spec("leiden cpm energy 0.002", part="cpm", gamma=0.002, weight="energy"),
    Spec("leiden cpm energy 0.005", part="cpm", gamma=0.005, weight="energy"),
]


class Evaluator:
    """Bond masks (with persistence) and partitions of a case's frames."""

    def __init__(self, case: Case):
        self.case = case
        self._keysets: dict = {}

    def _mask(self, fr: Frame, spec: Spec) -> np.ndarray:
        m = fr.frel >= spec.f if spec.f > 0 else np.ones(len(fr.i), bool)
        if spec.frame is not None:
            m &= fr.cos[spec.frame] >= math.cos(math.radians(spec.angle))
        return m

    def bonds(self, idx: int, spec: Spec) -> np.ndarray | None:
        """Mask of the bridges of frame idx that are bonds (None: not enough history)."""
        fr = self.case.frames[idx]
        m = self._mask(fr, spec)
        if spec.k > 1:
            if idx - spec.k + 1 < 0:
                return None
            for back in range(1, spec.k):
                prev = self.case.frames[idx - back]
                key = (idx - back, spec.frame, spec.angle, spec.f)
                if key not in self._keysets:
                    self._keysets[key] = prev.keys[self._mask(prev, spec)]
                m &= np.isin(fr.keys, self._keysets[key], assume_unique=True)
        return m

    def partition(self, idx: int, spec: Spec, tiles: int = 1):
        """(labels, percolating per particle, n, vprim) of frame idx, tiled ``tiles`` times."""
        fr = self.case.frames[idx]
        m = self.bonds(idx, spec)
        if m is None:
            return None
        i, j, dy = fr.i[m], fr.j[m], fr.dy[m]
        w = (fr.erel if spec.weight == "energy" else fr.frel)[m]
        n, L, vprim = fr.n, self.case.length, fr.vprim
        if tiles > 1:
            y = fr.pos[:, 1]
            s = np.round((y[j] - y[i] - dy) / L).astype(np.int64)   # j's image next to i is in copy c - s
            c = np.repeat(np.arange(tiles), len(i))
            i = np.tile(i, tiles) + c * n
            j = np.tile(j, tiles) + np.mod(c - np.tile(s, tiles), tiles) * n
            dy, w = np.tile(dy, tiles), np.tile(w, tiles)
            n, L, vprim = n * tiles, L * tiles, np.tile(vprim, tiles)
        if spec.part == "cc":
            labels, perc = components(n, i, j, dy, L)
            return labels, perc, n, vprim
        if len(i) == 0:
            labels = np.arange(n)
        elif spec.part == "louvain":
            labels = louvain(n, i, j, w, resolution=spec.gamma)
        elif spec.part == "leiden":
            labels = leiden(n, i, j, w / w.mean(), "modularity", spec.gamma)
        elif spec.part == "cpm":
            cg = self.case.cg
            labels = leiden(n, i, j, w * cg ** 2, "CPM", spec.gamma, np.full(n, cg ** 3))
        else:
            raise ValueError(spec.part)
        _, labels = np.unique(labels, return_inverse=True)
        return labels, community_percolation(labels, i, j, dy, L, n), n, vprim

