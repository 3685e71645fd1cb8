"""Acceptance: the default granule definition responds to the process. One tiny wet scene
(the 9 mm drum slice at CG2, We rule) run on the real engine at three liquid contents:
the granules' d50 must grow monotonically with the liquid, each step beyond the 95 %
bootstrap bands of its neighbours (frames resampled). The force-weighted CPM of an
earlier default failed this in spirit: its d50 moved by a few per cent for 4x the liquid,
because the capillary laws' touching force does not depend on the bridge volume."""

from __future__ import annotations

import numpy as np
import pandas as pd
import pytest

from ligwf.cli.main import main

from helpers import ROOT

pytestmark = [pytest.mark.engine, pytest.mark.mpi, pytest.mark.slow]

DRUM = ROOT / "tests" / "workflows" / "drum.yaml"
CONTENTS = (0.002, 0.01, 0.05)


def band(x: np.ndarray, rng: np.random.Generator) -> tuple[float, float]:
    draws = x[rng.integers(len(x), size=(2000, len(x)))].mean(axis=1)
    return float(np.percentile(draws, 2.5)), float(np.percentile(draws, 97.5))


def test_d50_grows_with_liquid_content_beyond_its_bands(tmp_path):
    out = tmp_path / "lc"
    sets = ["sweep.cg_levels=[2]", "sweep.rules=[weber]", "scene.process.settle_time=0.1",
            "scene.process.run_time=0.3", "scene.numerics.dump_interval=0.02",
            f"sweep.scene.liquid.liquid_content=[{','.join(map(str, CONTENTS))}]",
            "analysis.steady_after=0.0", "analysis.sensitivity_frames=0"]
    args = ["study", str(DRUM), "--out", str(out), "--np", "1", "--no-snapshots",
            "--mesh-cache", str(tmp_path / "meshes")]
    assert main([*args, *[x for s in sets for x in ("--set", s)]]) == 0
    kin = pd.read_csv(out / "analysis" / "kinetics.csv")
    rng = np.random.default_rng(3)
    rows = []
    for content in CONTENTS:
        sel = kin[kin["group"].str.contains(repr(content))]
        d50 = sel["d50"].to_numpy()
        assert len(d50) >= 10 and np.isfinite(d50).all(), (content, sel)
        rows.append((content, float(d50.mean()), *band(d50, rng)))
    for (c0, m0, lo0, hi0), (c1, m1, lo1, hi1) in zip(rows, rows[1:]):
        assert m1 > m0, rows
        assert lo1 > hi0, rows                   # disjoint bands: beyond the noise
