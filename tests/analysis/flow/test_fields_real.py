"""Cross-section fields of real LIGGGHTS dumps, end to end (the shared wet study: a CG3
We-scaled slice of the demo drum and its copy as a second replica): ``ligwf analyse``
writes the field archive and one ParaView image per case, the fields are physical (a
packed bed's solid fraction, temperatures >= 0, the bed's volume on the grid), a replica
that is a copy of the run has the same fields (floor 0), and the report's tables get the
field columns (nan here: the study has no CG1 case to compare with; its hand-written
manifests carry no run times, so the whole report is not run on it)."""

from __future__ import annotations

import json
import math
import shutil

import numpy as np
import pandas as pd

from ligwf.inference.field_errors import FIELD_ERRORS, field_floor
from ligwf.analysis.records.fields import fields_of, read_fields
from ligwf.cli.main import main
from ligwf.inference.field_tables import add_field_errors
from ligwf.study import layout
from wetdump import wet_study


def test_fields_of_real_wet_dumps(engine, tmp_path_factory, tmp_path):
    study = tmp_path / "study"
    shutil.copytree(wet_study(engine, tmp_path_factory), study)
    record = json.loads((study / "study.json").read_text())
    record["analysis"] = {"granules": "communities", "bootstrap": 50, "sensitivity_frames": 0}
    (study / "study.json").write_text(json.dumps(record))
    assert main(["analyse", str(study), "--no-vtu"]) == 0
    analysis = study / layout.ANALYSIS_DIR
    fields = read_fields(analysis / layout.FIELDS_DATA)
    assert set(fields) == {"cg3-weber-r0", "cg3-weber-r1"}
    for cid, cf in fields.items():
        assert (analysis / layout.field_image(cid)).is_file()
        assert cf.frames >= 2
        f = fields_of(cf.mean())
        assert 0.3 < np.nanmax(f["solid_fraction"]) < 0.74      # a packed bed, not denser
        material = f["solid_fraction"] >= 0.1
        assert np.all(f["temperature"][material] >= 0)
        assert np.all(np.isfinite(f["speed"][material]))
        # every particle's volume is on the grid but what the kernel spreads past its edge
        total = f["solid_fraction"].sum() * cf.grid.spacing**2 * cf.grid.length
        assert 0.8 < total / bed_volume(study / cid) <= 1.0 + 1e-6
    # the image of a case the study no longer measures does not outlive a new analysis
    stale = analysis / layout.field_image("cg3-weber-r9")
    stale.write_text("an image of an earlier analysis")
    assert main(["analyse", str(study), "--no-vtu"]) == 0
    assert not stale.exists() and all((analysis / layout.field_image(c)).is_file() for c in fields)
    r0, r1 = fields["cg3-weber-r0"], fields["cg3-weber-r1"]
    assert np.array_equal(r0.moments, r1.moments)
    assert field_floor([r0, r1], "field_solid_error").value == 0.0
    assert [w.kernel for w in r0.window_means] == [1.0, 2.0, 4.0]
    assert r0.omega != 0 and r0.radius > 0
    # no CG1 case in this study: the report's field errors are nan, with their columns
    cases = pd.DataFrame([{"case_id": c, "group": f.group, "cg": f.cg, "rule": f.rule}
                          for c, f in fields.items()])
    conditions = cases.groupby(["group", "cg", "rule"]).size().rename("replicas").reset_index()
    cases, cond = add_field_errors(cases, conditions, fields, 20, 1, 2.0)
    for name in FIELD_ERRORS:
        assert {name, f"{name}_lo", f"{name}_floor", f"{name}_vs_floor"} <= set(cond)
        assert math.isnan(cond[name].iloc[0]) and cond[f"{name}_vs_floor"].iloc[0] == "–"


def bed_volume(case_dir) -> float:
    """The particles' volume in the case's last particle dump, m^3."""
    from ligwf.analysis.frames.dumps import read_particles

    dumps = sorted((case_dir / layout.POST_DIR).glob("particles_*.vtu"),
                   key=lambda p: int(p.stem.split("_")[1]))
    return float(read_particles(dumps[-1], 0, 1.0).volumes.sum())
