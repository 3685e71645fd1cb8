"""ligwf.analysis.granules.screen_study on study folders in the states the screen leaves:
which run is a condition's, what its manifest says, and nothing measured where nothing ran."""

from __future__ import annotations

import json
import math

from ligwf.analysis.granules.screen_study import (PHASE2, case_folder, measure_phase1,
                                                  measure_phase2, status_of)
from ligwf.study import layout


def _run(folder, manifest: dict):
    folder.mkdir(parents=True)
    (folder / layout.MANIFEST_FILE).write_text(json.dumps(manifest))
    return folder


def test_a_condition_is_its_first_seed_and_its_manifest_says_status_cost_and_reason(tmp_path):
    first = _run(tmp_path / "S1" / "cg1-none-r0",
                 {"status": "killed", "core_seconds": 1800.0, "reason": "wall time"})
    _run(tmp_path / "S1" / "cg1-none-r1", {"status": "done", "core_seconds": 60.0})
    (tmp_path / "S2" / "cg1-none-r0").mkdir(parents=True)          # no manifest: not run
    assert case_folder(tmp_path, "S1") == first
    assert case_folder(tmp_path, "S2") is None
    assert case_folder(tmp_path, "S3") is None
    assert status_of(first) == ("killed", 1800.0, "wall time")
    status, core_s, reason = status_of(tmp_path / "S1" / "cg1-none-r1")
    assert (status, reason) == ("done", "") and core_s == 60.0
    _run(tmp_path / "S4" / "cg1-none-r0", {"status": "failed"})
    assert math.isnan(status_of(tmp_path / "S4" / "cg1-none-r0")[1])


def test_nothing_is_measured_where_nothing_ran(tmp_path):
    assert measure_phase1(tmp_path, {"S1": ("model", "placed nuclei")}) is None
    assert measure_phase2(tmp_path) is None
    (tmp_path / PHASE2).mkdir()                     # phase 2 begun, no run written yet
    phase2 = measure_phase2(tmp_path)
    assert phase2 is not None and phase2.runs.empty and phase2.rows.empty
