#!/usr/bin/env python3
"""Measure candidate granule definitions against the acceptance criteria (a)-(e).

Usage (the cases are ligwf case folders with ``scene.json`` and ``post/`` dumps)::

    PYTHONPATH=/tmp/gd/ref .venv/bin/python scripts/measure_granule_definitions.py \
        --base CG1_CASE_AT_THE_REFERENCE_CONDITION \
        --series CG1_CASE_LOW CG1_CASE_MID CG1_CASE_HIGH \
        --cg-series CGn_CASE_LOW CGn_CASE_MID CGn_CASE_HIGH \
        [--tiles 2 4] [--steady 0.25] [--boot 1000] [--speed-tiles 1 4 16]

The measurement of docs/results/granule_definitions.md (cases of ``ligwf run
workflows/granules.yaml --out /tmp/gd/lc --np 2 --set "sweep.cg_levels=[1,2]" --set
"sweep.rules=[weber]" --set sweep.replicas=1 --set scene.numerics.dump_interval=0.02 --set
scene.process.run_time=1.5 --set "sweep.scene.liquid.liquid_content=[0.01,0.02,0.04]"``)::

    L=/tmp/gd/lc; PYTHONPATH=/tmp/gd/ref .venv/bin/python scripts/measure_granule_definitions.py \
        --base $L/cg1-none-r0_liquid_content-0.02 \
        --series $L/cg1-none-r0_liquid_content-0.0{1,2,4} \
        --cg-series $L/cg2-weber-r0_liquid_content-0.0{1,2,4} --speed-tiles 1 4 16

Needs python-igraph and leidenalg in the venv (``pip install python-igraph leidenalg``).
``--base`` gives (a), (b), (c) and the speed table; ``--series`` (three liquid contents or
fill levels of one scene, in process order) gives (d); ``--cg-series`` (the same three
conditions at CG level n, We-scaled) gives (e) against ``--series``.

Definitions used (see docs/results/granule_definitions.md):

* bridge: a dumped pair whose washino/easo capillary force (ligwf.liquids.bridges, from
  the dumped overlap) is > 0;
* relative bridge force f_rel = F / (2 pi R* gamma cos theta), the force over the force of a
  touching bridge of the same pair: dimensionless, the same under every CG rule;
* velocity frames: ``lab``; ``rot`` = v - omega x r (the drum's rigid rotation, axis and
  omega from scene.json, centre on the axis through the origin); ``flow`` = v minus the
  mean velocity of the particles within 3 particle diameters (periodic along the axis);
* persistence k: the bond (with its force/angle filter) holds in k successive dumps;
* partitions: ``cc`` connected components, ``louvain`` (networkx, resolution 1),
  ``leiden`` (igraph Leiden, modularity, resolution 1), ``cpm`` (igraph Leiden, constant
  Potts model with resolution gamma; edge weight f_rel * n^2 and node weight n^3 at CG level
  n, which keeps the granule volume scale of CPM CG-neutral);
* a granule percolates when it closes a cycle around the periodic axis;
* d50: volume-weighted median of the volume-equivalent diameters (physical volume, m^3,
  NOT divided by n^3) of granules with >= 2 particles; for (e) also with a common cut
  (granules >= 2 particles of the coarsest level, at every level); bands: 95 % bootstrap over steady
  frames (frames resampled with replacement);
* steady frames: dumps after the first ``--steady`` fraction of production (production
  starts at the first dump: ligwf defines the dumps after the settle runs).
"""

from __future__ import annotations

import argparse
import json
import math
import random
import sys
import time
import zlib
from dataclasses import dataclass, replace
from pathlib import Path

import numba
import numpy as np
from scipy.spatial import cKDTree

from ligwf.analysis.frames.dumps import discover_frames, read_contacts, read_particles
from ligwf import liquids as _liquids
from ligwf.scene.axis import Axis


def capillary(model, *args):
    """The registered liquid model's capillary bridge force (ligwf.liquids registry)."""
    return _liquids.get(model).capillary_force(*args)


# --------------------------------------------------------------------------- frames


@dataclass
class Frame:
    step: int
    n: int
    ids: np.ndarray
    pos: np.ndarray
    vel: np.ndarray
    radii: np.ndarray
    vprim: np.ndarray        # particle volume, m^3 (physical: NOT divided by n^3, see below)
    i: np.ndarray            # bridged pairs (rows), F > 0
    j: np.ndarray
    dy: np.ndarray           # minimum-image displacement y_j - y_i along the axis, m
    force: np.ndarray        # N
    frel: np.ndarray         # F / (2 pi R* gamma cos theta)
    erel: np.ndarray         # rupture work / (F0 R*) (ligwf.analysis.granules.bridge_law.relative_energy)
    keys: np.ndarray         # id1 * big + id2 (id1 < id2), for persistence
    cos: dict                # velocity frame -> cos(angle) per bridge (1 for zero speed)


@dataclass
class Case:
    path: Path
    cg: float
    rule: str
    length: float
    axis: int
    omega: float
    liquid_content: float
    diameter: float
    frames: list             # all production frames, in step order
    steady: list             # indices into frames


def _cos(vi, vj):
    dot = np.einsum("ij,ij->i", vi, vj)
    nn = np.sqrt(np.einsum("ij,ij->i", vi, vi) * np.einsum("ij,ij->i", vj, vj))
    out = np.ones(len(dot))
    ok = nn > 0
    out[ok] = dot[ok] / nn[ok]
    return out


def _relative_energy(p, i, j, gap, model, gamma, theta, content):
    """The bridge's relative rupture work (the default CPM weight since 2026-11-28)."""
    from ligwf.analysis.granules.bridge_law import Liquid, relative_energy

    return relative_energy(p, i, j, gap, Liquid(model, gamma, theta, float(content)))


def load_case(path: Path, steady_fraction: float, flow_radii=(3.0,)) -> Case:
    scene = json.loads((path / "scene.json").read_text())
    s = scene["scaled"]
    axis = Axis(s.get("axis", "y")).index
    if axis != 1:
        raise SystemExit(f"{path}: only drums along y are handled")
    length = float(s["drum_length"])
    omega = float(s.get("omega", 2 * math.pi * float(s["rpm"]) / 60.0))
    theta = math.radians(float(s["contact_angle_deg"]))   # compensated input: engine applies it
    gamma = float(s["surface_tension"])
    model = s["liquid_model"]
    settle, run = int(s["settle_steps"]), int(s["run_steps"])
    # production starts with the first dump (the dumps are defined after the settle runs)
    files = [f for f in discover_frames(path) if f.contacts is not None]
    frames = []
    big = 10 ** 7
    for f in files:
        p = read_particles(f.particles)
        c = read_contacts(f.contacts)
        i, j = p.index_of(c.id1), p.index_of(c.id2)
        content = p.liquid_content if p.liquid_content is not None else np.full(len(p), s["liquid_content"])
        gap = -c.delta
        F = np.asarray(capillary(model, p.radii[i], p.radii[j], gap, gamma, theta,
                                 content[i], content[j]), float)
        keep = F > 0
        i, j, F = i[keep], j[keep], F[keep]
        reff = p.radii[i] * p.radii[j] / (p.radii[i] + p.radii[j])
        frel = F / (2 * math.pi * reff * gamma * math.cos(theta))
        erel = _relative_energy(p, i, j, gap[keep], model, gamma, theta, s["liquid_content"])
        y = p.positions[:, 1]
        d = y[j] - y[i]
        dy = d - length * np.round(d / length)
        lo, hi = np.minimum(p.ids[i], p.ids[j]), np.maximum(p.ids[i], p.ids[j])
        frames.append(Frame(f.step, len(p), p.ids, p.positions, p.velocities, p.radii,
                            p.volumes, i, j, dy, F, frel, erel,
                            lo * big + hi, {}))
    case = Case(path, float(s["cg"]), str(s["rule"]), length, axis, omega,
                float(s["liquid_content"]), float(np.mean(frames[0].radii) * 2) if frames else 0.0,
                frames, [])
    t0 = frames[0].step + steady_fraction * run
    case.steady = [k for k, fr in enumerate(frames) if fr.step >= t0]
    _velocity_frames(case, flow_radii)
    return case


def _velocity_frames(case: Case, flow_radii=(3.0,)) -> None:
    """cos(angle) per bridge in the lab frame, the drum frame and against the local flow."""
    L = case.length
    for fr in case.frames:
        v, r = fr.vel, fr.pos
        fr.cos["lab"] = _cos(v[fr.i], v[fr.j])
        # rigid rotation about +y (fix move/mesh rotate axis 0 1 0, period > 0): omega y x r
        wr = case.omega * np.stack([r[:, 2], np.zeros(len(r)), -r[:, 0]], axis=1)
        vr = v - wr
        fr.cos["rot"] = _cos(vr[fr.i], vr[fr.j])
        # local mean flow within 3 diameters, periodic along y
        box = 1.0
        pts = np.stack([r[:, 0] + 0.5 * box, np.mod(r[:, 1], L), r[:, 2] + 0.5 * box], axis=1)
        tree = cKDTree(pts, boxsize=[box, L, box])
        for rad in flow_radii:
            nb = tree.query_ball_point(pts, rad * case.diameter)
            mean = np.empty_like(v)
            for a, lst in enumerate(nb):
                mean[a] = v[lst].mean(axis=0)
            vf = v - mean
            fr.cos["flow" if rad == 3.0 else f"flow@{rad:g}"] = _cos(vf[fr.i], vf[fr.j])


def rotation_check(case: Case) -> tuple[float, float]:
    """Mean |v - omega x r| / mean |v| over steady frames for +omega and -omega (the
    right sign makes the bed nearly still in the drum frame)."""
    out = []
    for sign in (1.0, -1.0):
        num = den = 0.0
        for k in case.steady:
            fr = case.frames[k]
            r = fr.pos
            wr = sign * case.omega * np.stack([r[:, 2], np.zeros(len(r)), -r[:, 0]], axis=1)
            num += np.linalg.norm(fr.vel - wr, axis=1).mean()
            den += np.linalg.norm(fr.vel, axis=1).mean()
        out.append(num / den)
    return out[0], out[1]


# --------------------------------------------------------------------------- graphs


@numba.njit(cache=True)
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


@numba.njit(cache=True)
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


# --------------------------------------------------------------------------- candidates


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


def frame_metrics(labels, perc, vprim):
    """largest share (volume), any percolating granule, d50 (m, granules >= 2), mean size
    (particles) of granules >= 2, and the volumes of the granules >= 2 (m^3)."""
    members = np.bincount(labels)
    vol = np.bincount(labels, weights=vprim)
    flag = np.zeros(len(members), bool)
    np.logical_or.at(flag, labels, perc)
    big = members >= 2
    largest = vol.max() / vol.sum()
    anyperc = bool(np.any(flag & big))
    return largest, anyperc, d50_of(vol[big]), float(members[big].mean()) if big.any() else 1.0, vol[big]


def d50_of(vols, cut=0.0):
    """Volume-weighted median volume-equivalent diameter (m) of the granules >= cut (m^3)."""
    v = np.sort(vols[vols >= cut])
    if len(v) == 0:
        return float("nan")
    cum = np.cumsum(v) / v.sum()
    return float(np.cbrt(6.0 * v[min(np.searchsorted(cum, 0.5 - 1e-12), len(v) - 1)] / math.pi))


def boot_band(x, nboot, rng, conf=0.95):
    x = np.asarray(x, float)
    x = x[np.isfinite(x)]
    if len(x) == 0:
        return float("nan"), float("nan"), float("nan")
    draws = x[rng.integers(len(x), size=(nboot, len(x)))].mean(axis=1)
    a = 50 * (1 - conf)
    return float(x.mean()), float(np.percentile(draws, a)), float(np.percentile(draws, 100 - a))


EDGES_PER_DECADE = 5


def gsd_rows(vols_per_frame, vp):
    """Volume-weighted GSD per frame on decade-aligned log bins of granule volume."""
    lo = math.floor(math.log10(vp) * EDGES_PER_DECADE - 0.5) + 0.5
    edges = 10.0 ** (np.arange(lo, lo + 8 * EDGES_PER_DECADE + 1) / EDGES_PER_DECADE)
    rows = []
    for v in vols_per_frame:
        idx = np.clip(np.searchsorted(edges, v, side="right") - 1, 0, len(edges) - 2)
        h = np.bincount(idx, weights=v, minlength=len(edges) - 1)
        rows.append(h / h.sum() if h.sum() > 0 else h)
    return np.array(rows)


def run_spec(ev: Evaluator, spec: Spec, frames=None, tiles=1, timing=False):
    frames = ev.case.steady if frames is None else frames
    out = {"largest": [], "perc": [], "d50": [], "mean_size": [], "vols": [], "time": []}
    for idx in frames:
        t0 = time.perf_counter()
        res = ev.partition(idx, spec, tiles)
        dt = time.perf_counter() - t0
        if res is None:
            continue
        labels, perc, n, vprim = res
        lg, pc, d50, ms, vols = frame_metrics(labels, perc, vprim)
        for k, v in zip(("largest", "perc", "d50", "mean_size", "vols", "time"),
                        (lg, pc, d50, ms, vols, dt)):
            out[k].append(v)
    return out


# --------------------------------------------------------------------------- report


def fmt(x, p=3):
    if x is None or (isinstance(x, float) and math.isnan(x)):
        return "nan"
    return "inf" if math.isinf(x) else f"{x:.{p}g}"


def main(argv=None):
    ap = argparse.ArgumentParser(description=__doc__, formatter_class=argparse.RawDescriptionHelpFormatter)
    ap.add_argument("--base", type=Path, required=True)
    ap.add_argument("--series", type=Path, nargs="*", default=[])
    ap.add_argument("--cg-series", type=Path, nargs="*", default=[])
    ap.add_argument("--tiles", type=int, nargs="*", default=[2, 4])
    ap.add_argument("--steady", type=float, default=0.25)
    ap.add_argument("--boot", type=int, default=1000)
    ap.add_argument("--community-stride", type=int, default=2,
                    help="use every k-th steady frame for community methods on tiled frames")
    ap.add_argument("--speed-tiles", type=int, nargs="*", default=[1, 4, 16])
    ap.add_argument("--only", nargs="*", default=None, help="candidate names to run")
    args = ap.parse_args(argv)
    rng = np.random.default_rng(12345)
    specs = [s for s in CANDIDATES if args.only is None or s.name in args.only]

    t_load = time.perf_counter()
    base = load_case(args.base, args.steady, flow_radii=(3.0, 2.4, 3.6))
    series = [load_case(p, args.steady) if p.resolve() != args.base.resolve() else base for p in args.series]
    cgs = [load_case(p, args.steady) for p in args.cg_series]
    print(f"# loaded in {time.perf_counter() - t_load:.1f} s")
    for c in [base] + [c for c in series if c is not base] + cgs:
        nb = np.mean([len(c.frames[k].i) / c.frames[k].n for k in c.steady])
        fr = c.frames[c.steady[0]]
        print(f"# case {c.path.name}: CG{c.cg:g} {c.rule}, {fr.n} particles, liquid {c.liquid_content}, "
              f"{len(c.frames)} production dumps, {len(c.steady)} steady, bridges/particle {nb:.2f}, "
              f"dump interval {(c.frames[1].step - c.frames[0].step)} steps")
    rp, rm = rotation_check(base)
    print(f"# drum frame check: mean|v - w x r| / mean|v| = {rp:.3f} (+omega), {rm:.3f} (-omega)")
    # common size cut for (e): granules of >= 2 particles of the coarsest level, in m^3
    cut = 2.0 * max(float(c.frames[0].vprim.max()) for c in [base] + series + cgs)
    print(f"# (e) common cut: granules >= {cut:.3g} m^3 (2 particles of the coarsest level) at every level")
    ev = {id(base): Evaluator(base)}
    for c in series + cgs:
        ev.setdefault(id(c), Evaluator(c))

    rows = []
    for spec in specs:
        # one generator per candidate: its bands do not depend on which others run
        rng = np.random.default_rng([12345, zlib.crc32(spec.name.encode())])
        comm = spec.part != "cc"
        r = {"spec": spec}
        res = run_spec(ev[id(base)], spec)
        r["perc_frac"] = float(np.mean(res["perc"]))
        r["largest"] = float(np.mean(res["largest"]))
        r["d50"] = boot_band(res["d50"], args.boot, rng)
        r["mean_size"] = float(np.mean(res["mean_size"]))
        r["t_frame"] = float(np.median(res["time"]))
        r["a"] = (1 - r["perc_frac"]) >= 0.9 and r["largest"] < 0.10
        # (b) sensitivity
        ratios = []
        for label, p in spec.perturbations():
            rp_ = run_spec(ev[id(base)], p)
            d = np.nanmean(rp_["d50"]) if np.isfinite(rp_["d50"]).any() else float("nan")
            ratios.append((label, d / r["d50"][0]))
        r["sens"] = ratios
        worst = max((max(x, 1 / x) for _, x in ratios if math.isfinite(x) and x > 0), default=float("nan"))
        r["b_worst"] = worst
        r["b"] = bool(math.isfinite(worst) and worst < 1.5) if ratios else None
        # (c) tiling
        frames = base.steady[::args.community_stride] if comm else base.steady
        ref = run_spec(ev[id(base)], spec, frames=frames)
        vp = float(base.frames[0].vprim.min())
        g1 = gsd_rows(ref["vols"], vp)
        draws = g1[rng.integers(len(g1), size=(args.boot, len(g1)))].mean(axis=1)
        blo, bhi = np.percentile(draws, 2.5, axis=0), np.percentile(draws, 97.5, axis=0)
        d1 = boot_band(ref["d50"], args.boot, rng)
        tiles = {}
        for m in args.tiles:
            t = run_spec(ev[id(base)], spec, frames=frames, tiles=m)
            gm = gsd_rows(t["vols"], vp).mean(axis=0)
            dev = np.abs(gm - g1.mean(axis=0))
            half = 0.5 * (bhi - blo)
            with np.errstate(divide="ignore", invalid="ignore"):
                q = np.where(dev > 1e-9, dev / half, 0.0)
            outside = float(np.nanmax(q))        # GSD change / half band, worst bin
            tiles[m] = (float(np.nanmean(t["d50"])), float(outside), float(np.mean(t["mean_size"])),
                        float(np.mean(t["largest"])))
        r["tiles"] = tiles
        r["d50_1x"] = d1
        r["c"] = all(v[1] <= 1.0 for v in tiles.values())
        # (d) process response, (e) CG

        def summary(c, spec=spec, cut=cut):
            rr = run_spec(ev[id(c)], spec)
            return (boot_band(rr["d50"], args.boot, rng), float(np.mean(rr["largest"])),
                    float(np.mean(rr["perc"])),
                    boot_band([d50_of(v, cut) for v in rr["vols"]], args.boot, rng))

        dser = [summary(c) for c in series]
        r["series"] = dser
        if len(dser) >= 3:
            m = [x[0] for x in dser]
            up = all(m[k][1] > m[k - 1][2] for k in range(1, len(m)))
            down = all(m[k][2] < m[k - 1][1] for k in range(1, len(m)))
            r["d"] = up or down
        else:
            r["d"] = None
        dcg = [summary(c) for c in cgs]
        r["cg"] = dcg
        if dcg and len(dcg) == len(dser):
            r["cg_ratio_plain"] = [c[0][0] / s[0][0] for c, s in zip(dcg, dser)]
            q = [c[3][0] / s[3][0] for c, s in zip(dcg, dser)]
            r["cg_ratio"] = q
            # CG-neutral: the CGn/CG1 d50 ratio within a factor 1.5 at every condition, both
            # with each level's own >= 2 particle cut and with the common cut
            r["e"] = all(math.isfinite(x) and 1 / 1.5 < x < 1.5 for x in q + r["cg_ratio_plain"])
        else:
            r["cg_ratio"], r["e"] = [], None
        rows.append(r)
        print(f"# done {spec.name}", file=sys.stderr, flush=True)

    d_p = base.diameter
    yn = {True: "yes", False: "NO", None: "-"}
    print("\n## Summary (d50 in CG1 particle diameters d_p, 95 % bootstrap band)\n")
    print("| candidate | (a) perc. frames | (a) largest | d50/d_p [band] | (b) worst x | (c) d50 2x / 4x | "
          "(d) d50 by liquid | (e) CGn/CG1 d50: own cut / common cut | a | b | c | d | e |")
    print("|---|---|---|---|---|---|---|---|---|---|---|---|---|")
    for r in rows:
        d = r["d50"]
        tl = " / ".join(fmt(r["tiles"][m][0] / d_p) for m in sorted(r["tiles"]))
        ds = " -> ".join(fmt(x[0][0] / d_p) for x in r["series"])
        cr = ", ".join(fmt(x, 2) for x in r.get("cg_ratio_plain", [])) + " / " + ", ".join(
            fmt(x, 2) for x in r["cg_ratio"])
        print(f"| {r['spec'].name} | {r['perc_frac']:.0%} | {r['largest']:.1%} | {fmt(d[0]/d_p)} "
              f"[{fmt(d[1]/d_p)}, {fmt(d[2]/d_p)}] | {fmt(r['b_worst'])} | {tl} | {ds} | {cr} | "
              f"{yn[r['a']]} | {yn[r['b']]} | {yn[r['c']]} | {yn[r['d']]} | {yn[r['e']]} |")

    print("\n## (b) d50 ratio to the base value per perturbed threshold\n")
    for r in rows:
        print(f"- {r['spec'].name}: " + ", ".join(f"{lab} {fmt(x)}" for lab, x in r["sens"]))

    print("\n## (c) tiling: d50/d_p, worst GSD bin change / half 95 % band (<= 1 passes; inf: a bin empty in every 1x frame filled), "
          "mean granule size (particles), largest share\n")
    for r in rows:
        d1 = r["d50_1x"]
        print(f"- {r['spec'].name}: 1x {fmt(d1[0]/d_p)} [{fmt(d1[1]/d_p)}, {fmt(d1[2]/d_p)}], "
              f"size {r['mean_size']:.1f}; " +
              "; ".join(f"{m}x {fmt(v[0]/d_p)}, change/half-band {fmt(v[1])}, size {v[2]:.1f}, largest {v[3]:.1%}"
                        for m, v in sorted(r["tiles"].items())))

    print("\n## (d)/(e) per condition: d50/d_p [band], largest share, percolating frames\n")
    for r in rows:
        parts = []
        for lab, lst in (("CG1", r["series"]), ("CGn", r["cg"])):
            parts.append(lab + " " + "; ".join(
                f"{fmt(x[0][0]/d_p)} [{fmt(x[0][1]/d_p)},{fmt(x[0][2]/d_p)}] {x[1]:.1%} {x[2]:.0%}" for x in lst))
        print(f"- {r['spec'].name}: " + " | ".join(parts) + "; common-cut d50/d_p CG1 "
              + ", ".join(fmt(x[3][0] / d_p) for x in r["series"]) + " CGn "
              + ", ".join(fmt(x[3][0] / d_p) for x in r["cg"]) + "; plain CGn/CG1 d50 "
              + ", ".join(fmt(x, 2) for x in r.get("cg_ratio_plain", [])))

    # speed of the community algorithms (and components for scale)
    print("\n## speed: median s per frame on one core (bond mask + partition + percolation test; frames tiled along the axis for the larger N)\n")
    speed_specs = [s for s in specs if s.name in ("cc rot 10", "cc persist k5", "louvain",
                                                  "leiden modularity", "leiden cpm 0.05")]
    idx = base.steady[len(base.steady) // 2: len(base.steady) // 2 + 3]
    e0 = ev[id(base)]
    print("| method | " + " | ".join(f"N={base.frames[idx[0]].n * m}" for m in args.speed_tiles)
          + " | extrapolated 360k (linear in N) | frames/s at 360k |")
    print("|---|" + "---|" * (len(args.speed_tiles) + 2))
    for s in speed_specs:
        ts = []
        for m in args.speed_tiles:
            use = idx if m <= 4 else idx[:1]
            tt = []
            for k in use:
                t0 = time.perf_counter()
                e0.partition(k, s, m)
                tt.append(time.perf_counter() - t0)
            ts.append(float(np.median(tt)))
        nmax = base.frames[idx[0]].n * args.speed_tiles[-1]
        t360 = ts[-1] * 360000 / nmax
        print(f"| {s.name} | " + " | ".join(f"{t:.3g}" for t in ts) + f" | {t360:.3g} s | {1/t360:.2g} |")


if __name__ == "__main__":
    main()
