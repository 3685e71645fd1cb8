"""Shared test helpers: repository paths and running the real engine in a case folder.

(Kept out of conftest.py: tests/slurm has its own conftest, and ``from conftest import``
would pick whichever pytest imported last.)
"""

from __future__ import annotations

import subprocess
from dataclasses import replace
from pathlib import Path

import numpy as np

ROOT = Path(__file__).resolve().parent.parent
DRUM = ROOT / "tests" / "workflows" / "drum.yaml"
WET_POLY = ROOT / "tests" / "workflows" / "wet_poly.yaml"


def run_liggghts(engine, case_dir: Path, nprocs: int = 1, timeout: float = 300) -> subprocess.CompletedProcess:
    """Run ``in.liggghts`` in ``case_dir``; stdout+stderr captured together."""
    return subprocess.run(engine.command("in.liggghts", nprocs), cwd=case_dir, text=True,
                          errors="replace", stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          timeout=timeout, stdin=subprocess.DEVNULL)


def tiled(p, c, tiles: int, length: float):
    """The periodic frame repeated ``tiles`` times along y; pairs across the boundary are
    rewired to the neighbouring copy (ids of copy k: id + k * (max id))."""
    n, big = len(p), int(p.ids.max())
    pos = np.concatenate([p.positions + [0.0, k * length, 0.0] for k in range(tiles)])
    out_p = replace(p, ids=np.concatenate([p.ids + k * big for k in range(tiles)]),
                    types=np.tile(p.types, tiles), positions=pos,
                    velocities=np.tile(p.velocities, (tiles, 1)), radii=np.tile(p.radii, tiles),
                    liquid_content=None if p.liquid_content is None
                    else np.tile(p.liquid_content, tiles))
    a, b = p.index_of(c.id1), p.index_of(c.id2)
    d = p.positions[b, 1] - p.positions[a, 1]
    shift = np.round(d / length).astype(np.int64)      # b's nearest image is in copy k - shift
    id1, id2 = [], []
    for k in range(tiles):
        id1.append(c.id1 + k * big)
        id2.append(c.id2 + np.mod(k - shift, tiles) * big)
    out_c = replace(c, id1=np.concatenate(id1), id2=np.concatenate(id2),
                    delta=np.tile(c.delta, tiles))
    assert n * tiles == len(out_p)
    return out_p, out_c
