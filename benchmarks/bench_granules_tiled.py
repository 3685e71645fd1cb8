"""Granule definitions on REAL frames tiled to paper scale, one core: results per second.

A case's dumps (particles + contacts) are repeated ``--tiles`` times along the periodic
axis (pairs across the boundary rewired to the neighbouring copy, the helper of
tests/helpers.py), then timed, best of ``--repeat``:

* the default definition (``AnalysisSettings()``: ``granules: held``, hold_time 1 s) in its
  steady state: per result one
  new frame's bridge keys, its presence runs and the components of the held bridges, over
  a window of hold_time / dump interval frames (the keys of the earlier frames are
  cached, as :class:`ligwf.analysis.granules.case.GranuleAnalysis` does); beside it what
  intersecting the window's key sets costs (the code before the presence runs);
* rupture-work CPM communities by compiled Louvain (``granules: communities``, the earlier
  default) on the case's last frame, and its parts (bond test, rupture work, CPM);
* the source study's components (lab frame, 30 deg);
* reading: a real dump pair of the case, scaled by the tile count (the tiled frames are
  never written, so their reading is estimated, not timed), and the default end to end:
  its per-result work plus the two dump pairs a held result reads.

CPU seconds (``time.process_time``: the machine is shared, wall clock is printed too) are
the figure to compare. Target (#24): the default >= 1 result/s at ~360k particles.

Usage: python benchmarks/bench_granules_tiled.py CASE_DIR [--tiles 30] [--repeat 3]
(30 tiles of the 18 mm we_vs_bo CG1 case = 358,890 particles.)
"""

from __future__ import annotations

import argparse
import sys
import time
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT / "tests"))

from helpers import tiled  # noqa: E402
from ligwf.analysis import granules_numba  # noqa: E402
from ligwf.analysis.frames.checks import plan_frames  # noqa: E402
from ligwf.analysis.frames.dumps import read_contacts, read_particles  # noqa: E402
from ligwf.analysis.granules.bonds import bonded_contacts  # noqa: E402
from ligwf.analysis.granules.bridge_law import relative_energy  # noqa: E402
from ligwf.analysis.granules.case import RunFacts  # noqa: E402
from ligwf.analysis.granules.communities import cpm_labels  # noqa: E402
from ligwf.analysis.granules.definitions import bond_criterion, identify_granules  # noqa: E402
from ligwf.analysis.granules.persistent import (Frame, bridge_keys, held_through,  # noqa: E402
                                                persistent_labels, presence_run)
from ligwf.scene.settings import AnalysisSettings  # noqa: E402
from ligwf.study.case import CaseFolder  # noqa: E402


def timed(fn, repeat: int):
    """(best CPU s, best wall s, last result) of ``repeat`` calls."""
    cpu, wall, out = [], [], None
    for _ in range(repeat):
        c, w = time.process_time(), time.perf_counter()
        out = fn()
        cpu.append(time.process_time() - c)
        wall.append(time.perf_counter() - w)
    return min(cpu), min(wall), out


def line(label: str, cpu: float, wall: float, extra: str = "") -> None:
    print(f"  {label:>34}: {cpu:6.3f} s CPU = {1 / cpu:6.2f} results/s "
          f"(wall {wall:6.3f} s){extra}")


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", type=Path)
    ap.add_argument("--tiles", type=int, default=30)
    ap.add_argument("--repeat", type=int, default=3)
    ap.add_argument("--held-results", type=int, default=3,
                    help="steady-state held results timed (after the window is filled)")
    args = ap.parse_args()
    case = CaseFolder.open(args.case)
    facts = RunFacts.of_case(case)
    granules_numba.warm_up((facts.liquid.model,))
    length = case.scaled.drum.length
    frames = [f for f in plan_frames(case).frames if f.contacts]

    def load(ff):
        p = read_particles(ff.particles, ff.step, facts.dt)
        c = read_contacts(ff.contacts, ff.step)
        return tiled(p, c, args.tiles, length) if args.tiles > 1 else (p, c)

    pt, ct = load(frames[-1])
    motion = replace(facts.motion, length=length * args.tiles)
    default = AnalysisSettings()
    print(f"{args.case.name} step {frames[-1].step} tiled {args.tiles}x: {len(pt):,} particles, "
          f"{len(ct):,} contacts; one core, best of {args.repeat}; default definition: "
          f"{default.granules}, hold_time {default.hold_time:g} s")
    compute = held_bench(frames, load, facts, motion, args.held_results, default)
    c, w, _ = timed(lambda: (read_particles(frames[-1].particles, frames[-1].step, facts.dt),
                             read_contacts(frames[-1].contacts, frames[-1].step)), args.repeat)
    reading = c * args.tiles
    print(f"  {'reading one dump pair':>34}: {c:6.3f} s CPU at {len(pt) // args.tiles:,} "
          f"particles: ~{reading:.3f} s at {len(pt):,} (linear estimate)")
    if compute is not None:
        # a held result at frame t reads two dump pairs (GranuleAnalysis: frame t itself,
        # and frame t + hold_time for its bridge keys; the keys in between are cached)
        total = compute + 2 * reading
        print(f"  {'default end to end, per result':>34}: {total:6.3f} s CPU = "
              f"{1 / total:6.2f} results/s (held {compute:.3f} s + 2 dump pairs read "
              f"~{2 * reading:.3f} s)")
    cpm = AnalysisSettings(granules="communities")
    cpu, wall, ident = timed(lambda: identify_granules(pt, ct, facts.liquid, cpm, facts.cg,
                                                       motion), args.repeat)
    line("communities (earlier default)", cpu, wall,
         f", {int(ident.labels.max()) + 1:,} granules")
    i, j, _, rows = bonded_contacts(pt, ct, facts.liquid, bond_criterion(cpm), with_rows=True)
    for label, fn in (
            ("  bond test", lambda: bonded_contacts(pt, ct, facts.liquid, bond_criterion(cpm),
                                                    with_rows=True)),
            ("  rupture work", lambda: relative_energy(pt, i, j, -ct.delta[rows], facts.liquid))):
        c, w, _ = timed(fn, args.repeat)
        print(f"  {label:>34}: {c:6.3f} s CPU (wall {w:6.3f} s)")
    weight = relative_energy(pt, i, j, -ct.delta[rows], facts.liquid) * facts.cg ** 2
    nw = np.full(len(pt), float(facts.cg) ** 3)
    c, w, _ = timed(lambda: cpm_labels(len(pt), i, j, weight, nw, cpm.resolution), args.repeat)
    print(f"  {'  CPM (compiled Louvain)':>34}: {c:6.3f} s CPU (wall {w:6.3f} s)")
    comp = AnalysisSettings(granules="components", velocity_frame="lab", max_velocity_angle=30.0)
    cpu, wall, ident = timed(lambda: identify_granules(pt, ct, facts.liquid, comp, facts.cg,
                                                       motion), args.repeat)
    line("components lab 30 deg", cpu, wall, f", {int(ident.labels.max()) + 1:,} granules")


def held_bench(frames, load, facts, motion, results: int,
               held: AnalysisSettings) -> float | None:
    """``granules: held`` (``held``'s hold_time) in its steady state over the case's first
    frames: per result the work a new frame adds once the window is filled."""
    interval = (frames[1].step - frames[0].step) * facts.dt
    span = max(1, int(round(held.hold_time / interval)))
    if len(frames) < span + 1 + results:
        print(f"  held: the case has {len(frames)} frames, a window needs {span + 1}")
        return None
    keys, runs = [], []
    for ff in frames[:span]:                      # fill the window (not timed)
        p, c = load(ff)
        keys.append(bridge_keys(Frame(p, c), facts.liquid))
        runs.append(presence_run(keys[-1], keys[-2] if len(keys) > 1 else None,
                                 runs[-1] if runs else None))
    cpu, wall, inter = [], [], []
    for k in range(results):
        first = load(frames[k])
        new = load(frames[k + span])
        c0, w0 = time.process_time(), time.perf_counter()
        keys.append(bridge_keys(Frame(*new), facts.liquid))
        runs.append(presence_run(keys[-1], keys[-2], runs[-1]))
        bridges = keys[-1][runs[-1] >= span + 1]
        ident = persistent_labels([Frame(*first)], [bridges], motion)
        cpu.append(time.process_time() - c0)
        wall.append(time.perf_counter() - w0)
        c0 = time.process_time()
        assert np.array_equal(held_through(keys[-span - 1:]), bridges)
        inter.append(time.process_time() - c0)
    line(f"held, {held.hold_time:g} s ({span + 1}-frame window)", min(cpu), min(wall),
         f", {int(ident.labels.max()) + 1:,} granules; intersecting the window instead: "
         f"{min(inter):.3f} s CPU more")
    return min(cpu)


if __name__ == "__main__":
    main()
