"""A tiny study with a cohesionless twin, end to end: the twin runs beside its wet case,
the analysis measures both with every candidate definition, and the report prints the
control table and the verdict of the study's own definition (real engine runs)."""

from __future__ import annotations

import json

import pandas as pd
import pytest

from ligwf.analysis.granules.control_verdict import verdict
from ligwf.cli.main import main

from helpers import ROOT

pytestmark = [pytest.mark.engine, pytest.mark.mpi, pytest.mark.slow]

TINY = ROOT / "tests" / "workflows" / "tiny_study.yaml"


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    out = tmp_path_factory.mktemp("controls") / "tiny"
    rc = main(["study", str(TINY), "--out", str(out), "--no-snapshots",
               "--set", "sweep.cg_levels=[1]", "--set", "sweep.controls=[cohesionless]",
               "--set", "scene.process.run_time=0.6", "--set", "scene.numerics.dump_interval=0.02",
               "--set", "analysis.granules=held", "--set", "analysis.hold_time=0.1"])
    assert rc == 0
    return out


def test_twin_runs_beside_its_case_with_the_bridge_forces_off(study):
    wet = json.loads((study / "cg1-none-r0" / "scene.json").read_text())
    twin = json.loads((study / "cg1-none-r0_cohesionless" / "scene.json").read_text())
    assert twin["varied"] == {"control": "cohesionless"}
    assert twin["scaled"]["surface_tension"] == pytest.approx(wet["scaled"]["surface_tension"] / 1e3)
    assert twin["scaled"]["viscosity"] == pytest.approx(wet["scaled"]["viscosity"] / 1e3)
    assert twin["scaled"]["seeds"] == wet["scaled"]["seeds"]
    for d in ("cg1-none-r0", "cg1-none-r0_cohesionless"):
        assert json.loads((study / d / "manifest.json").read_text())["status"] == "done"


def test_controls_table_measures_every_definition_on_both(study):
    table = pd.read_csv(study / "analysis" / "controls.csv")
    assert set(table["case_id"]) == {"cg1-none-r0"}
    assert set(table["twin_id"]) == {"cg1-none-r0_cohesionless"}
    assert table["definition"].iloc[0] == "study definition (held)"
    assert {"communities", "source_components_angle30", "held_0.25s"} <= set(table["definition"])
    # frame-wise components of every bridge: the whole wet bed, in the twin as well (bridges
    # form in both; only their forces differ): a definition blind to cohesion
    comp = table.set_index("definition").loc["bridge_components"]
    assert comp["share_10"] > 0.9 and comp["twin_share_10"] > 0.9
    # the stored verdict is the pre-registered criteria applied to the stored numbers
    for _, r in table.iterrows():
        wet = {k: r[k] for k in r.index if not k.startswith("twin_")}
        twin = {k.removeprefix("twin_"): r[k] for k in r.index if k.startswith("twin_")}
        assert verdict(wet, twin, r["definition"]) == (bool(r["passes"]), r["verdict"])
    # the held definition is deterministic (no optimiser, contact order irrelevant)
    assert table.set_index("definition").loc["study definition (held)", "ari_order"] == 1.0


def test_report_prints_the_control_section_and_its_verdict(study):
    md = (study / "report" / "summary.md").read_text()
    table = pd.read_csv(study / "analysis" / "controls.csv")
    assert "## Granule controls (wet bed / cohesionless twin)" in md
    assert table["verdict"].iloc[0] in md
    html = (study / "report" / "index.html").read_text()
    assert "Granule controls" in html and "cg1-none-r0_cohesionless" in html


def test_held_gsd_is_invariant_to_tiling(study):
    """``granules: held`` on the wet case's real frames (0.1 s windows), the frames tiled
    2x (12 diameters: the base) and then 2x and 4x again along the periodic axis:
    deterministic, so every copy holds the same granules; the volume-weighted GSD of the
    non-percolating granules and the bed share of percolating ones agree to rounding (a
    granule wrapped around the base box joins its copies into one wrapped around the longer
    box: still percolating, the same share)."""
    from dataclasses import replace

    import numpy as np

    from ligwf.analysis.gsd import bins as gsd
    from ligwf.analysis.granules.control_run import load_series
    from ligwf.analysis.granules.persistent import Frame, bridge_keys, persistent_labels
    from helpers import tiled

    series = load_series(study / "cg1-none-r0")
    length = series.facts.box_length
    liquid, motion = series.facts.liquid, series.facts.motion
    base = [tiled(f.particles, f.contacts, 2, length) for f in series.frames[10:22]]
    L, span = 2 * length, series.frames_in(0.1)
    v1 = float(base[0][0].volumes.mean())
    edges = gsd.log_edges(v1, 500 * v1, 5)

    def hist(tiles):
        out = []
        for k in range(0, len(base) - span, 2):
            window = [(p, c) if tiles == 1 else tiled(p, c, tiles, L) for p, c in base[k:k + span + 1]]
            wf = [Frame(p, c) for p, c in window]
            ident = persistent_labels(wf, [bridge_keys(f, liquid) for f in wf],
                                      replace(motion, length=L * tiles))
            vol = np.bincount(ident.labels, weights=wf[0].particles.volumes)
            members = np.bincount(ident.labels)
            keep = gsd.counted(members, ident.percolating, 2)
            perc = vol[ident.percolating].sum() / vol.sum()
            out.append(np.append(gsd.histogram(vol[keep], edges)[1], perc))
        return np.array(out)

    one = hist(1)
    assert one[:, :-1].sum() > 0                           # held granules, not singletons
    for tiles in (2, 4):
        np.testing.assert_allclose(hist(tiles), one, rtol=1e-9, atol=1e-12)
