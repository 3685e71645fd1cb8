"""Granule identification speed: networkx reference vs compiled fast path, and a whole frame.

Usage: ``.venv/bin/python benchmarks/bench_granules.py [--sizes 13000 45000 360000]
[--real CASE_DIR]`` (one core; prints, never asserts).

Synthetic frames: N particles of 1 mm on a jittered simple-cubic lattice in a box periodic
along y, each bonded to lattice neighbours so that every particle has about 5 contacts
(coordination number 5, i.e. 2.5 N contact rows), gaps spread from 2% overlap to beyond the
rupture distance, and a rotating-drum-like velocity field with noise so the velocity-angle
criterion splits the bed into many granules (like a real flowing bed). The same frame is
also written as particle and contact ``.vtu`` files (meshio, binary) to time the whole
frame: read + identify + GSD.

Per size it prints the time per frame of
* reference: compiled bond criterion + networkx BFS components + networkx BFS unwrap +
  table (the ``implementation="reference"`` path of ligwf.analysis.runner);
* fast:      one compiled pass doing bond criterion + union-find + unwrap, then the table
  (the default path of ligwf.analysis.runner);
* floor:     one streaming pass over the contact arrays identification needs (id1, id2,
  delta: a sum over each, in memory), the least any implementation must do;
* read contacts: reading one contact dump with the default (fast) reader;
and the ratios reference/fast (target >= 100x at 360k) and fast/floor (target <= 25x),
plus whole frames per second (read particles + contacts, identify, GSD; target >= 2 at
360k). The split line shows where the time goes: the reference's parts (compiled bond
criterion, networkx components, networkx unwrap; and the numpy evaluation of the bond
criterion, ``bonded_contacts_reference``) and the fast path's fused pass and table.

The compiled kernels (numba) are compiled or loaded from the cache once by ``warm_up()``
before anything is timed, so no row includes JIT compilation. All of them, the bond
kernels of each liquid law included, are cached per installation: only the first process
after an install or an edit compiles them (``benchmarks/bench_kernel_cache.py``).
``--model`` picks the synthetic frames' law (washino: the force law is provably positive
and skipped; easo: it is evaluated for every bond).
"""

from __future__ import annotations

import argparse
import json
import math
import tempfile
import time
from pathlib import Path

import numpy as np

from ligwf.analysis import dumps_numba
from ligwf.analysis import granules_numba
from ligwf.analysis.gsd import bins as gsd
from ligwf.analysis.frames.dumps import (ContactFrame, ParticleFrame, discover_frames, read_contacts,
                         read_particles)
from ligwf.analysis.granules.bonds import (BondCriterion, bonded_contacts, bonded_contacts_reference,
                                          granule_table, identify, label_reference, unwrap_reference)
from ligwf.analysis.granules.bridge_law import Liquid, relative_energy
from ligwf.analysis.granules.communities import cpm_labels
from ligwf.analysis.granules.definitions import Motion, bond_criterion, identify_granules
from ligwf.scene.axis import Axis
from ligwf.scene.settings import AnalysisSettings
from ligwf.scene.scaled import ScaledScene

R = 0.0005
#: the synthetic frames' liquid (``--model`` picks the law)
LIQUID = dict(surface_tension=0.024, contact_angle_rad=math.radians(30.0), liquid_content=0.02)


def synthetic_frame(n: int, seed: int = 1) -> tuple[ParticleFrame, ContactFrame, float]:
    """A frame of about n particles with ~5 contacts per particle; returns (p, c, L_y)."""
    rng = np.random.default_rng(seed)
    side = round(n ** (1 / 3))
    nx_, ny, nz = side, max(2, n // (side * side)), side
    n = nx_ * ny * nz
    a = 2 * R * 1.02
    ix, iy, iz = np.unravel_index(np.arange(n), (nx_, ny, nz))
    pos = np.column_stack([ix, iy, iz]) * a + rng.normal(0, 0.02 * R, (n, 3))
    length = ny * a
    pos[:, 1] = np.mod(pos[:, 1], length)
    # drum-like rotation about y plus noise: neighbours mostly co-move, some do not
    centre = pos.mean(axis=0)
    vel = np.column_stack([-(pos[:, 2] - centre[2]), np.zeros(n), pos[:, 0] - centre[0]]) * 3.0
    vel += rng.normal(0, 0.01, (n, 3))
    # forward lattice neighbours (+x, +y periodic, +z), each kept with probability 5/6
    pairs = []
    for dx, dy, dz in ((1, 0, 0), (0, 1, 0), (0, 0, 1)):
        jx, jy, jz = ix + dx, (iy + dy) % ny, iz + dz
        ok = (jx < nx_) & (jz < nz)
        j = np.ravel_multi_index((jx[ok], jy[ok], jz[ok]), (nx_, ny, nz))
        pairs.append(np.column_stack([np.nonzero(ok)[0], j]))
    pairs = np.concatenate(pairs)
    pairs = pairs[rng.uniform(size=len(pairs)) < 2.5 * n / len(pairs)]   # 2.5 n rows
    m = len(pairs)
    delta = rng.uniform(-2.5e-4, 2e-5, m)          # rupture of 1 mm spheres is ~1.6e-4 m
    ids = np.arange(1, n + 1, dtype=np.int64)
    p = ParticleFrame(Path("synthetic"), 0, 0.0, ids, np.ones(n, np.int32), pos, vel,
                      np.full(n, R), np.full(n, 0.02))
    lo, hi = np.minimum(pairs[:, 0], pairs[:, 1]), np.maximum(pairs[:, 0], pairs[:, 1])
    c = ContactFrame(Path("synthetic"), 0, lo + 1, hi + 1, delta)
    return p, c, length


def write_frame(p: ParticleFrame, c: ContactFrame, folder: Path, step: int = 1000) -> None:
    """The frame as LIGGGHTS-like particle and contact .vtu dumps (meshio, binary)."""
    import meshio

    n = len(p)
    meshio.write(folder / f"particles_{step}.vtu", meshio.Mesh(
        p.positions.astype(np.float32), [("vertex", np.arange(n).reshape(-1, 1))],
        point_data={"id": p.ids.astype(np.int32), "type": p.types, "v": p.velocities,
                    "radius": p.radii, "f_surfaceLiquidContent": p.liquid_content}),
        file_format="vtu", binary=True, compression=None)
    i, j = c.id1 - 1, c.id2 - 1
    pts = np.concatenate([p.positions[i], p.positions[j]]).astype(np.float32)
    m = len(c)
    lines = np.column_stack([np.arange(m), np.arange(m) + m])
    meshio.write(folder / f"contacts_{step}.vtu", meshio.Mesh(
        pts, [("line", lines)], cell_data={
            "vel1": [p.velocities[i]], "vel2": [p.velocities[j]],
            "id1": [c.id1.astype(float)], "id2": [c.id2.astype(float)],
            "force": [np.zeros((m, 3))], "force_normal": [np.zeros((m, 3))],
            "delta": [c.delta]}), file_format="vtu", binary=True, compression=None)


def timed(fn, repeat: int = 1) -> tuple[float, object]:
    best, out = math.inf, None
    for _ in range(repeat):
        t0 = time.perf_counter()
        out = fn()
        best = min(best, time.perf_counter() - t0)
    return best, out


def granules_of(p, c, length, liquid, fast: bool):
    """The granule table of one frame, as ligwf.analysis.runner computes it."""
    ident = identify(p, c, liquid, BondCriterion(), 1, length, "fast" if fast else "reference")
    return granule_table(p, ident.labels, 1.0, ident.unwrapped_axis, 1, 0.0, length, ident.percolating)


def stream_floor(c: ContactFrame) -> float:
    return float(c.id1.sum() + c.id2.sum() + c.delta.sum())


def whole_frame(folder: Path, step: int, length: float, liquid) -> int:
    p = read_particles(folder / f"particles_{step}.vtu")
    c = read_contacts(folder / f"contacts_{step}.vtu")
    table = granules_of(p, c, length, liquid, fast=True)
    v = table["primary_volume"].to_numpy()
    gsd.histogram(v, gsd.log_edges(v.min(), v.max(), 5))
    gsd.percentile_diameters(v)
    return len(table)


def report(label: str, p, c, length, liquid, folder: Path | None, step: int,
           skip_reference: bool) -> None:
    t_fast, table = timed(lambda: granules_of(p, c, length, liquid, True), 3)
    t_floor, _ = timed(lambda: stream_floor(c), 5)
    if skip_reference:
        t_ref = math.nan
    else:
        t_ref, ref_table = timed(lambda: granules_of(p, c, length, liquid, False), 1)
        assert ref_table["members"].tolist() == table["members"].tolist()
    line = (f"{label:>16}: N={len(p):>7,} contacts={len(c):>8,} granules={len(table):>7,} | "
            f"reference {t_ref:8.3f} s  fast {t_fast * 1e3:8.1f} ms  ratio {t_ref / t_fast:7.1f}x | "
            f"floor {t_floor * 1e3:6.2f} ms  fast/floor {t_fast / t_floor:6.1f}x")
    if folder is not None:
        t_read, _ = timed(lambda: read_contacts(folder / f"contacts_{step}.vtu"), 3)
        t_whole, _ = timed(lambda: whole_frame(folder, step, length, liquid), 3)
        line += (f" | read contacts {t_read * 1e3:7.1f} ms  fast/read {t_fast / t_read:5.2f}x"
                 f" | whole frame {t_whole:6.3f} s = {1 / t_whole:5.2f} frames/s")
    print(line, flush=True)
    # where the time goes
    t_fused, ident = timed(lambda: identify(p, c, liquid, BondCriterion(), 1, length), 3)
    t_tab, _ = timed(lambda: granule_table(p, ident.labels, 1.0, ident.unwrapped_axis, 1, 0.0, length,
                                           ident.percolating), 3)
    t_bond, (i, j, _) = timed(lambda: bonded_contacts(p, c, liquid, BondCriterion()), 3)
    t_bond_np, _ = timed(lambda: bonded_contacts_reference(p, c, liquid, BondCriterion()), 1)
    if skip_reference:
        t_lr = t_ur = math.nan
    else:
        t_lr, labels = timed(lambda: label_reference(len(p), i, j), 1)
        t_ur, _ = timed(lambda: unwrap_reference(p.positions, labels, i, j, 1, length), 1)
    print(f"{'':>16}  split: fast = fused bond+components+unwrap pass {t_fused * 1e3:6.1f} ms "
          f"(force law {'skipped, provably > 0' if ident.force is None else 'evaluated'}) + table "
          f"{t_tab * 1e3:5.1f} ms | reference = bond criterion {t_bond * 1e3:6.1f} ms (numpy "
          f"{t_bond_np * 1e3:6.1f} ms) + components {t_lr:6.3f} s + unwrap {t_ur:6.3f} s + table"
          f" | percolating granules {int(ident.percolating.sum())}", flush=True)


def report_communities(label: str, p, c, length: float, liquid: Liquid) -> None:
    """Time per frame of the communities definition (the default until 2026-12-02; Leiden CPM of the rupture-work-weighted
    bridges, igraph, graph built from numpy arrays) with its split: bond test with forces,
    the rupture-work quadrature, the CPM partition, the components of the intra-community
    bonds; frames/s on one core (target >= 0.5 at 360k)."""
    definition = AnalysisSettings(granules="communities")
    motion = Motion(Axis.Y, None, Axis.Y, length)
    t_all, ident = timed(lambda: identify_granules(p, c, liquid, definition, 1.0, motion), 1)
    t_bond, (i, j, force, rows) = timed(
        lambda: bonded_contacts(p, c, liquid, bond_criterion(definition), with_rows=True), 1)
    t_work, w = timed(lambda: relative_energy(p, i, j, -c.delta[rows], liquid), 1)
    nw = np.ones(len(p))
    t_cpm, _ = timed(lambda: cpm_labels(len(p), i, j, w, nw, definition.resolution), 1)
    print(f"{'':>16}  communities (CPM, compiled Louvain, {definition.community_weight} weight, gamma "
          f"{definition.resolution:g}): {t_all:6.3f} s = {1 / t_all:5.2f} frames/s | "
          f"bonds+forces {t_bond * 1e3:6.1f} ms, rupture work {t_work * 1e3:6.1f} ms, "
          f"CPM {t_cpm:6.3f} s, granules {int(ident.labels.max()) + 1:,}", flush=True)


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("--sizes", type=int, nargs="*", default=[13000, 45000, 360000])
    ap.add_argument("--real", type=Path, default=None, help="a case folder with dumps")
    ap.add_argument("--skip-reference-above", type=int, default=10**9)
    ap.add_argument("--model", default="washino", help="liquid model of the synthetic frames")
    args = ap.parse_args()
    t0 = time.perf_counter()
    granules_numba.warm_up((args.model,))
    dumps_numba.warm_up()
    print(f"compiled kernels warmed up (JIT or cache load) in {time.perf_counter() - t0:.1f} s, "
          "outside every timed row")
    print("one core; times are best of 3 (fast, whole frame) / 1 (reference) runs")
    for n in args.sizes:
        p, c, length = synthetic_frame(n)
        with tempfile.TemporaryDirectory() as tmp:
            write_frame(p, c, Path(tmp))
            report(f"synthetic {n // 1000}k", p, c, length, Liquid(args.model, **LIQUID), Path(tmp), 1000,
                   n > args.skip_reference_above)
        report_communities(f"synthetic {n // 1000}k", p, c, length, Liquid(args.model, **LIQUID))
    if args.real is not None:
        scaled = ScaledScene.from_dict(json.loads((args.real / "scene.json").read_text())["scaled"])
        f = discover_frames(args.real)[-1]
        p, c = read_particles(f.particles), read_contacts(f.contacts)
        report(f"real {args.real.name}", p, c, scaled.drum.length, Liquid.from_scaled(scaled),
               f.particles.parent, f.step, False)
        report_communities(f"real {args.real.name}", p, c, scaled.drum.length,
                           Liquid.from_scaled(scaled))


if __name__ == "__main__":
    main()
