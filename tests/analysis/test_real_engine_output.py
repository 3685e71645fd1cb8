"""The analysis on real engine output, in the fast lane: ``tests/data/cg3_slice`` is a CG3
We-scaled run of the test drum (222 particles of 3 mm, 30 rpm, LIGGGHTS 3.8.0 on one rank;
the command that made it is in ``tests/data/README.md``) with its particle and contact
dumps at three steps. The dumps are what the committed input asks for, and ``ligwf
analyse`` on them gives flow metrics and granules that agree with the frames they come from
and with the values measured when the data was committed."""

from __future__ import annotations

import json
import shutil

import numpy as np
import pandas as pd
import pytest

from helpers import ROOT
from ligwf.analysis.flow.frame import DrumGeometry, frame_flow
from ligwf.analysis.frames.dumps import discover_frames, read_contacts, read_particles
from ligwf.analysis.granules.case import RunFacts
from ligwf.analysis.granules.definitions import identify_granules
from ligwf.cli.main import main
from ligwf.scene.settings import AnalysisSettings
from ligwf.study import layout
from ligwf.study.case import CaseFolder

DATA = ROOT / "tests" / "data" / "cg3_slice"
CASE = "cg3-weber-r0"
STEPS = [13618, 20427, 27236]


@pytest.fixture(scope="module")
def run():
    """(case folder, [(particles, contacts)] of every committed frame)."""
    case = CaseFolder.open(DATA / CASE)
    frames = [(read_particles(f.particles, dt=case.scaled.numerics.dt), read_contacts(f.contacts))
              for f in discover_frames(case.path)]
    return case, frames


def test_the_dumps_are_the_run_of_the_committed_input(run):
    case, frames = run
    s = case.scaled
    assert (s.cg, s.rule, s.particles.count) == (3.0, "weber", 222)
    assert [p.step for p, _ in frames] == STEPS
    assert all(step % s.numerics.dump_every == 0 for step in STEPS)
    radius, length = 0.5 * s.drum.diameter, s.drum.length
    for p, c in frames:
        assert np.array_equal(p.ids, np.arange(1, 223))
        np.testing.assert_allclose(p.radii, 1.5e-3, rtol=1e-6)     # 1 mm beads x 3
        x, y, z = p.positions.T
        assert np.all(np.hypot(x, z) + p.radii <= radius * (1 + 1e-3))   # inside the shell
        assert np.all((y >= 0) & (y <= length))                     # the periodic slice
        assert np.all(p.liquid_content >= 0) and np.all(p.liquid_content <= s.liquid_values.liquid_content)
        # every pair the contact dump lists: two particles whose gap is the dumped overlap
        assert len(c) > 200 and np.all(c.id1 != c.id2)
        i, j = p.index_of(c.id1), p.index_of(c.id2)
        d = p.positions[i] - p.positions[j]
        d[:, 1] -= length * np.round(d[:, 1] / length)              # the nearest image
        gap = np.linalg.norm(d, axis=1) - p.radii[i] - p.radii[j]
        np.testing.assert_allclose(gap, -c.delta, atol=2e-6)       # float32 positions
        assert np.all(gap <= 0.1 * 3e-3 * 1.1 + 2e-6)              # within bridge reach


def test_ligwf_analyse_on_real_engine_output(run, tmp_path):
    case, frames = run
    study = tmp_path / "study"
    shutil.copytree(DATA, study)
    record = json.loads((study / "study.json").read_text())
    record["analysis"].update(bootstrap=50, sensitivity_frames=0)
    (study / "study.json").write_text(json.dumps(record))
    assert main(["analyse", str(study), "--no-vtu"]) == 0
    out = study / layout.ANALYSIS_DIR

    per_frame = pd.read_csv(out / layout.FRAMES_TABLE)
    assert per_frame["step"].tolist() == STEPS and set(per_frame["status"]) == {"ok"}
    assert per_frame["particles"].tolist() == [222] * 3
    assert per_frame["contacts"].tolist() == [len(c) for _, c in frames]
    assert (per_frame["bonds"] <= per_frame["contacts"]).all()
    granules = pd.read_parquet(out / layout.GRANULES_TABLE)
    for (_, row), (p, _) in zip(per_frame.iterrows(), frames):
        g = granules[granules["step"] == row["step"]]
        assert len(g) == row["granules"]
        assert g["members"].sum() == 222                            # every particle once
        assert g["volume"].sum() == pytest.approx(p.volumes.sum(), rel=1e-9)

    flow = pd.read_csv(out / layout.FLOW_TABLE).iloc[0]
    # fewer than 6 frames: the steady window is the last 0.75 of production (2 frames)
    assert flow["frames"] == 2 and flow["steady_fraction"] == 0.25
    geo = DrumGeometry.from_scaled(case.scaled)
    flows = [frame_flow(p, geo) for p, _ in frames[1:]]
    assert flow["angle_of_repose"] == pytest.approx(
        np.mean([f.angle_of_repose for f in flows]), rel=1e-9)
    # the values measured when the data was committed: a rolling bed, half its frames rigid
    # (the angle 48.099 until 2026-12-07, when the surface strips moved onto a grid anchored
    # at the bed's centre line that ends at the span: the former grid's last strip ran
    # past it, tests/analysis/flow/test_surface_resolution.py)
    assert flow["angle_of_repose"] == pytest.approx(48.624, abs=1e-3)
    assert "angle_of_repose_mean" not in flow.index        # one name for the one mean
    assert flow["rigid_frame_share"] == 0.5
    # (0.017129 before the anchored strips moved the fitted surface, 0.017114 until the
    # thickness became mass-equivalent, without the fitted surface in it: issue 44 item 1,
    # tests/analysis/flow/test_layer_resolution.py)
    assert flow["flowing_layer_thickness_mean"] == pytest.approx(0.010282, abs=1e-6)
    omega_r = geo.omega * geo.radius                                 # 0.079 m/s at the wall
    assert 0.5 * omega_r < flow["rms_speed_mean"] < 2 * omega_r
    summary = pd.read_csv(out / layout.GSD_SUMMARY_TABLE).iloc[0]
    # the GSD's bed share: granules of >= min_particles that do not wrap the periodic
    # axis, as a share of the bed's volume, averaged over the steady frames
    shares = []
    for _, g in granules[granules["step"] > flow["steady_from_step"]].groupby("step"):
        kept = (g["members"] >= record["analysis"]["min_particles"]) & ~g["percolating"]
        shares.append(g.loc[kept, "volume"].sum() / g["volume"].sum())
    assert len(shares) == 2 and summary["granule_share"] == pytest.approx(np.mean(shares))
    # the slice is 3 beads long: in the last frame 4 granules wrap around it
    assert granules.loc[granules["step"] == STEPS[-1], "percolating"].sum() == 4
    assert per_frame["granules"].tolist() == [86, 85, 90]


@pytest.mark.parametrize("definition", [
    AnalysisSettings(granules="components", max_velocity_angle=30.0),        # the source study
    AnalysisSettings(granules="components", velocity_frame="drum", max_velocity_angle=10.0),
    AnalysisSettings(granules="communities"),
], ids=["components-lab-30", "components-drum-10", "communities"])
def test_compiled_granules_equal_the_reference_on_real_frames(run, definition):
    """The compiled kernels against their plain reference (networkx components, the
    Python Louvain) on real engine frames, in the fast lane: the same granules, the same
    wrap flags and unwrapped positions."""
    case, frames = run
    facts = RunFacts.of_case(case)
    sizes = []
    for p, c in frames:
        fast = identify_granules(p, c, facts.liquid, definition, case.cg, facts.motion)
        ref = identify_granules(p, c, facts.liquid, definition, case.cg, facts.motion,
                                "reference")
        np.testing.assert_array_equal(fast.labels, ref.labels)
        np.testing.assert_array_equal(fast.percolating, ref.percolating)
        np.testing.assert_allclose(fast.unwrapped_axis, ref.unwrapped_axis, atol=1e-15)
        sizes.append(np.bincount(fast.labels).max())
    assert max(sizes) >= 2                      # real bonds: not every particle alone
