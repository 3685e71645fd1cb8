"""The default granule definition on a REAL frame tiled to paper scale, one core.

A case's last dump (particles + contacts) is repeated ``--tiles`` times along its periodic
axis (pairs across the boundary rewired to the neighbouring copy, the helper of
tests/analysis/test_definitions.py), then the default definition (rupture-work CPM by
compiled Louvain) and the source study's components are timed (best of 3), and the CPM
quality of the compiled Louvain is compared with igraph's Leiden on the same graph.
Target (issue 11): communities >= 0.5 frames/s, components >= 2 frames/s at 360k.

Usage: python benchmarks/bench_granules_tiled.py CASE_DIR [--tiles 30]
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

from analysis.test_definitions import tiled  # noqa: E402
from ligwf.analysis import granules_numba  # noqa: E402
from ligwf.analysis.granules.case import RunFacts  # noqa: E402
from ligwf.analysis.granules.communities import cpm_labels, cpm_labels_reference, cpm_quality  # noqa: E402
from ligwf.analysis.granules.definitions import cpm_weights, identify_granules  # noqa: E402
from ligwf.scene.settings import AnalysisSettings  # noqa: E402
from ligwf.analysis.frames.dumps import discover_frames, read_contacts, read_particles  # noqa: E402
from ligwf.study.case import CaseFolder  # noqa: E402


def best_of(fn, runs: int = 3):
    times, out = [], None
    for _ in range(runs):
        t = time.perf_counter()
        out = fn()
        times.append(time.perf_counter() - t)
    return min(times), out


def main() -> None:
    ap = argparse.ArgumentParser(description=__doc__.splitlines()[0])
    ap.add_argument("case", type=Path)
    ap.add_argument("--tiles", type=int, default=30)
    args = ap.parse_args()
    case = CaseFolder.open(args.case)
    facts = RunFacts.of_case(case)
    granules_numba.warm_up((facts.liquid.model,))
    length = case.scaled.drum_length
    f = [f for f in discover_frames(args.case) if f.contacts][-1]
    p, c = read_particles(f.particles, f.step, facts.dt), read_contacts(f.contacts, f.step)
    pt, ct = tiled(p, c, args.tiles, length) if args.tiles > 1 else (p, c)
    motion = replace(facts.motion, length=length * args.tiles)
    print(f"{args.case.name} step {f.step} tiled {args.tiles}x: {len(pt):,} particles, "
          f"{len(ct):,} contacts; one core, best of 3")
    for label, d in (("communities (default)", AnalysisSettings()),
                     ("components lab 30 deg", AnalysisSettings(
                         granules="components", velocity_frame="lab", max_velocity_angle=30.0))):
        t, ident = best_of(lambda d=d: identify_granules(pt, ct, facts.liquid, d, facts.cg, motion))
        print(f"  {label:>22}: {t:6.3f} s per frame = {1 / t:6.2f} frames/s, "
              f"{int(ident.labels.max()) + 1:,} granules")
    i, j, w, nw = cpm_weights(pt, ct, facts.liquid, facts.cg)
    gamma = AnalysisSettings().resolution
    t_fast, fast = best_of(lambda: cpm_labels(len(pt), i, j, w, nw, gamma), 1)
    t_ref, ref = best_of(lambda: cpm_labels_reference(len(pt), i, j, w, nw, gamma), 1)
    q_fast, q_ref = cpm_quality(fast, i, j, w, nw, gamma), cpm_quality(ref, i, j, w, nw, gamma)
    size = lambda lab: np.bincount(lab)[np.bincount(lab) > 1].mean()  # noqa: E731
    print(f"  CPM alone: compiled Louvain {t_fast:.3f} s, igraph Leiden {t_ref:.3f} s "
          f"({t_ref / t_fast:.1f}x); quality difference {(q_fast - q_ref) / w.sum():+.4f} of the "
          f"total edge weight; mean community {size(fast):.1f} vs {size(ref):.1f} particles")


if __name__ == "__main__":
    main()
