"""Cost of the cross-section fields (ligwf.analysis.flow.fields) on a paper-scale frame.

A synthetic 360,000-particle frame in a 0.2 m drum (1 mm particles, kernel 2 mm, nodes
every 1 mm: 201 x 201): both passes of one frame (flux moments, then the fluctuation about
a mean field) with the fast deposit, and the bootstrap of the solid-fraction error (100
draws, two replicas against two of 20 frames each). CPU time (``time.process_time``: the machine is
shared, wall time says little). Prints the seconds; no assertion (a benchmark, not a test).

    PYTHONPATH=. .venv/bin/python benchmarks/bench_fields.py
"""

from __future__ import annotations

import time
from pathlib import Path

import numpy as np

from ligwf.analysis.flow.fields import (field_grid, flux_moments, fluctuation_moment,
                                        mean_velocity)
from ligwf.analysis.flow.frame import DrumGeometry
from ligwf.analysis.frames.dumps import ParticleFrame
from ligwf.inference.field_errors import field_intervals
from ligwf.analysis.records.fields import CaseFields

N, R, D, L, OMEGA = 360_000, 0.1, 0.001, 0.06, 2.0


def frame(seed: int) -> ParticleFrame:
    rng = np.random.default_rng(seed)
    r = R * 0.95 * np.sqrt(rng.random(N))
    t = np.pi * (1 + rng.random(N))           # the lower half of the drum
    p = np.stack([r * np.cos(t), rng.random(N) * L, r * np.sin(t)], axis=1)
    c = np.cross(np.array([0.0, OMEGA, 0.0]), p) + rng.normal(0, 0.01, (N, 3))
    return ParticleFrame(Path("bench.vtu"), 0, 0.0, np.arange(1, N + 1), np.ones(N, np.int32),
                         p, c, np.full(N, D / 2), None)


def main() -> None:
    geo = DrumGeometry(R, "y", OMEGA, D)
    grid = field_grid(geo, 2 * D, L)
    fr = frame(0)
    t0 = time.process_time()
    flux = flux_moments(fr, geo, grid)
    t1 = time.process_time()
    fluctuation_moment(fr, geo, grid, mean_velocity(flux))
    t2 = time.process_time()
    print(f"{N} particles, {grid.nodes}x{grid.nodes} nodes: flux pass {t1 - t0:.2f} CPU s, "
          f"fluctuation pass {t2 - t1:.2f} CPU s per frame")
    rng = np.random.default_rng(1)
    base = np.concatenate([flux, flux[:1]])[None]
    cases = [CaseFields(f"c{k}", 1.0 if k < 2 else 2.0, "none", k % 2, "{}", grid,
                        np.arange(20), base * (1 + 0.01 * rng.normal(size=(20, 1, 1, 1))))
             for k in range(4)]
    t3 = time.process_time()
    iv = field_intervals(cases[2:], cases[:2], 100, 1)["field_solid_error"]
    print(f"field_solid_error bootstrap (100 draws, 2 vs 2 replicas x 20 frames): "
          f"{time.process_time() - t3:.2f} CPU s (value {iv.value:.3g})")


if __name__ == "__main__":
    main()
