"""The field criterion and the solid error in the report's tables, the null checks and the
section (ligwf.report.fields), on synthetic fields with known answers: a bed that turns
with the drum and carries a flowing layer on top (a band below the surface sliding at
``FLOW`` x omega R relative to the drum). A CG2 condition whose layer flows 20 % faster
differs by about 0.1 omega R there, decidedly beyond the noise; one that is CG1's own flow
does not; CG1 against CG1 finds nothing; a cohesionless twin that flows 30 % faster shows
up in the null check; the maps are drawn on shared scales."""

from __future__ import annotations

import json

import numpy as np
import pandas as pd
import pytest

from ligwf.analysis.flow.fields import case_fields
from ligwf.report.field_figures import group_figures, rotation_sense
from ligwf.inference.field_tables import add_field_errors, null_check, twin_cases
from ligwf.report.fields import fields_section
from ligwf.scene.axis import Axis
from test_fields import D1, DRUM_R, HEAD, LENGTH, OMEGA, WIDTH, geometry, lattice_frame

TWIN_GROUP = json.dumps({"control": "cohesionless"})
DRAWS = 100
FLOW = 0.5           # the layer's speed relative to the drum, omega R
LAYER = 0.015        # m, depth of the flowing band below the surface (v = 0)


def layer_frame(step: int, seed: int, scale: float):
    """A lattice frame turning with the drum whose top band flows along -u at ``scale`` x
    FLOW x omega R relative to it."""
    f = lattice_frame(D1, 2e-3, 4, step=step, noise=0.05, seed=seed)
    band = f.positions[:, 2] > -LAYER
    f.velocities[band, 0] -= scale * FLOW * OMEGA * DRUM_R
    return f


def synthetic(case_id: str, cg: float, rule: str, replica: int, group: str, scale: float,
              seed: int):
    frames = [layer_frame(k, seed + k, scale) for k in range(10)]
    # the drum's typical diameter is the CG level's (CG1 particles stand in for it): the
    # window means' kernels are then the same physical widths at every level
    return case_fields(frames, geometry(cg * D1), 2 * WIDTH, LENGTH,     # 61 x 61 nodes
                       {**HEAD, "case_id": case_id, "cg": cg, "rule": rule,
                        "replica": replica, "group": group})


@pytest.fixture(scope="module")
def study_fields():
    spec = [("cg1-none-r0", 1.0, "none", 0, "{}", 1.0),
            ("cg1-none-r1", 1.0, "none", 1, "{}", 1.0),
            ("cg2-weber-r0", 2.0, "weber", 0, "{}", 1.0),
            ("cg2-weber-r1", 2.0, "weber", 1, "{}", 1.0),
            ("cg2-bond-r0", 2.0, "bond", 0, "{}", 1.2),
            ("cg2-bond-r1", 2.0, "bond", 1, "{}", 1.2),
            ("cg1-none-r0_cohesionless", 1.0, "none", 0, TWIN_GROUP, 1.3),
            ("cg1-none-r1_cohesionless", 1.0, "none", 1, TWIN_GROUP, 1.3)]
    fields = {s[0]: synthetic(*s, seed=100 * k) for k, s in enumerate(spec)}
    cases = pd.DataFrame([{"case_id": s[0], "cg": s[1], "rule": s[2], "replica": s[3],
                           "group": s[4]} for s in spec])
    conditions = (cases.groupby(["group", "cg", "rule"], sort=True).size()
                  .rename("replicas").reset_index())
    return fields, cases, conditions


@pytest.fixture(scope="module")
def tables(study_fields):
    fields, cases, conditions = study_fields
    return add_field_errors(cases, conditions, fields, DRAWS, 7, 2.0)


def test_field_errors_enter_the_tables_with_the_contract_columns(tables):
    cases, cond = tables
    for name in ("field_error", "field_solid_error"):
        for sfx in ("", "_lo", "_hi", "_se", "_floor", "_floor_source", "_vs_floor"):
            assert f"{name}{sfx}" in cond
        assert name in cases
    for width in ("k1", "k2", "k4"):
        assert {f"field_error_{width}", f"field_error_{width}_lo", f"field_error_{width}_hi"} <= set(cond)
    row = cond.set_index(["group", "cg", "rule"])
    bond, weber = row.loc[("{}", 2.0, "bond")], row.loc[("{}", 2.0, "weber")]
    # a layer 20 % faster: 0.1 omega R where it flows freely, less where the kernel
    # smears its edge into the plug
    assert 0.07 < bond["field_error"] <= 0.1 and bond["field_error_lo"] > 0
    assert bond["field_error"] == bond["field_error_k2"] and bond["field_error_kernel"] == 2.0
    assert bond["field_error_vs_floor"] == "beyond"
    assert bond["field_error_floor_source"].startswith("CG1 vs CG1: first against second half")
    assert weber["field_error_lo"] == 0.0 and weber["field_error"] < 0.02
    assert weber["field_error_hi"] < bond["field_error_hi"]
    assert weber["field_error_vs_floor"] != "beyond"
    assert row.loc[("{}", 1.0, "none")]["field_error_vs_floor"] == "reference"
    # a wider kernel smears the layer's edge further: the error shrinks with the width
    assert bond["field_error_k4"] < bond["field_error_k1"]
    # a case's own (raw) error: against the mean of its group's CG1 cases
    by_id = cases.set_index("case_id")
    assert by_id.loc["cg2-bond-r0", "field_error"] == pytest.approx(bond["field_error"], abs=0.01)


def test_null_check_and_section(study_fields, tables, tmp_path):
    fields = study_fields[0]
    cases, cond = tables
    null = null_check(cases, fields, DRAWS, 7, 2.0).set_index("comparison")
    assert set(null.index) == {"CG1 vs CG1", "cohesionless twin vs wet CG1"}
    same, twin = null.loc["CG1 vs CG1"], null.loc["cohesionless twin vs wet CG1"]
    assert same["group"] == "{}" and same["runs"] == same["ref_runs"] == 2
    assert same["field_error_lo"] == 0.0 and same["field_error"] < 0.02
    assert np.isnan(same["field_solid_error"])
    assert twin["group"] == "{}" and twin["control"] == TWIN_GROUP
    assert 0.1 < twin["field_error"] <= 0.15 and twin["field_error_lo"] > 0.05
    assert twin["field_solid_error"] == pytest.approx(0.0, abs=1e-9)
    assert twin_cases(cases) == {"{}": ["cg1-none-r0_cohesionless", "cg1-none-r1_cohesionless"]}
    figs = group_figures(cases, fields, tmp_path, rotation_sense(Axis.Y, 3.0), twin_cases(cases))
    assert [p.name for _, p in figs] == ["fields_study_maps.png", "fields_study_differences.png"]
    assert all(p.stat().st_size > 10_000 for _, p in figs)
    md = fields_section(cond, null.reset_index(), fields,
                        [(t, f"figures/{p.name}") for t, p in figs], 2.0)
    assert "## Flow fields" in md and "cg2" not in md.split("| group")[0]
    assert "kernel 2 d [bounds] (verdict)" in md and "kernel 4 d" in md
    assert "fields_study_maps.png" in md and "Null checks" in md
    assert "| CG1 vs CG1 |" in md


def test_no_fields_no_errors(study_fields):
    _, cases, conditions = study_fields
    cases, cond = add_field_errors(cases, conditions, {}, 10, 1, 2.0)
    assert cond["field_error"].isna().all() and set(cond["field_error_vs_floor"]) == {"–"}
    assert "run `ligwf analyse` again" in fields_section(cond, pd.DataFrame(), {}, [])


def test_rotation_sense_on_the_maps():
    # axis y, (u, v) = (x, z): +y points away from the viewer, so omega > 0 is clockwise
    assert rotation_sense(Axis.Y, 1.0) == "clockwise"
    assert rotation_sense(Axis.Y, -1.0) == "counter-clockwise"
    assert rotation_sense(Axis.X, 1.0) == "counter-clockwise"


def test_only_the_recorded_archive_is_read(study_fields, tmp_path):
    """The report reads the field archive the analysis record lists, nothing else: a
    stale archive (not in the record) is ignored, an unreadable listed one is one line."""
    from ligwf.analysis.records.fields import fields_bytes, recorded_fields
    from ligwf.analysis.records.provenance import StaleAnalysis
    from ligwf.study import layout

    fields = study_fields[0]
    (tmp_path / layout.FIELDS_DATA).write_bytes(fields_bytes(list(fields.values())[:2]))
    (tmp_path / layout.ANALYSIS_RECORD).write_text(json.dumps({"outputs": {}}))
    assert recorded_fields(tmp_path) == {}
    (tmp_path / layout.ANALYSIS_RECORD).write_text(
        json.dumps({"outputs": {layout.FIELDS_DATA: [0, ""]}}))
    assert set(recorded_fields(tmp_path)) == {"cg1-none-r0", "cg1-none-r1"}
    (tmp_path / layout.FIELDS_DATA).write_bytes(b"not a zip")
    with pytest.raises(StaleAnalysis, match="not a field archive"):
        recorded_fields(tmp_path)
