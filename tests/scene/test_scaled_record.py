"""The scaled scene's on-disk record: nested in memory, the same flat mapping on disk.

A case folder stores ``ScaledScene.to_dict()`` and its content hash covers
``json.dumps(to_dict(), sort_keys=True)``: a changed byte would make every case of every
existing study look re-rendered. The pinned hashes below were computed by the flat
ScaledScene (before it was nested, commit 37c8116) and must never change.
"""

from __future__ import annotations

import json

import pytest

from ligwf.pipeline.prepare import render_case
from ligwf.scene.axis import Axis
from ligwf.scene.scaled import DERIVED_KEYS, ScaledScene
from ligwf.scene.workflow import load_workflow
from ligwf.study.layout import SCENE_FILE

from helpers import DRUM, ROOT, WET_POLY

DATA = ROOT / "tests" / "data"

#: content hashes (scaled record + rendered input + mesh) of the flat ScaledScene
PINNED = [
    (WET_POLY, (), "cg3-weber-r0",
     "3eddbf7a2f05970fd2bae1d8b6d685ee8302dc7b4b79050901026107ff4bdffa"),
    (DRUM, ("scene.liquid.model=washino", "scene.liquid.bridge_volume_fraction=0.2",
            "scene.liquid.max_liquid_content=0.1"), "cg2-weber-r0",
     "13aad0082af7112118232364e7b3c5bceb9ba85e954cda2dccc4d31fdab6d23e"),
    (DRUM, ("scene.liquid.placement=granules",
            "scene.liquid.wet_granules={count: 2, radius: 0.005}"), "cg1-none-r0",
     "08f56f60de7843d2d41bad52456d98513c3e5d031104d4e3d4dcfd5185fd7d97"),
]


@pytest.mark.parametrize("workflow, overrides, case_id, digest", PINNED,
                         ids=["wet-poly", "washino-fraction-cap", "wet-granules"])
def test_the_case_hash_of_a_known_scene_is_the_flat_records(workflow, overrides, case_id,
                                                            digest):
    wf = load_workflow(workflow, list(overrides))
    rendered = render_case(next(c for c in wf.cases if c.case_id == case_id))
    assert rendered.scene_hash == digest


@pytest.mark.parametrize("folder", ["cg3_slice/cg3-weber-r0", "ranks/demo_cg1_r0"])
def test_a_committed_flat_record_round_trips_byte_for_byte(folder):
    stored = json.loads((DATA / folder / SCENE_FILE).read_text())["scaled"]
    scaled = ScaledScene.from_dict(stored)
    assert scaled.to_dict() == stored
    assert (json.dumps(scaled.to_dict(), sort_keys=True)
            == json.dumps(stored, sort_keys=True))
    assert scaled.drum.axis is Axis.Y and scaled.drum.periodic_axis is Axis.Y


def test_derived_values_are_written_and_computed_not_stored():
    s = load_workflow(DRUM).cases[0].scaled()
    record = s.to_dict()
    assert {k: record[k] for k in DERIVED_KEYS} == {
        "rotation_period": s.drum.rotation_period, "rpm": s.drum.rpm,
        "froude": s.drum.froude, "rayleigh_time": s.particles.rayleigh_time}
    assert record["granules"] == s.contact_dumps and "contact_dumps" not in record
    assert ScaledScene.from_dict(record) == s


@pytest.mark.parametrize("key", sorted(DERIVED_KEYS))
def test_a_derived_value_that_does_not_follow_is_refused(key):
    record = load_workflow(DRUM).cases[0].scaled().to_dict()
    record[key] *= 1.5
    with pytest.raises(ValueError, match=key):
        ScaledScene.from_dict(record)


def test_a_missing_or_unknown_key_is_an_error_never_a_default():
    record = load_workflow(DRUM).cases[0].scaled().to_dict()
    with pytest.raises(TypeError, match="dt"):
        ScaledScene.from_dict({k: v for k, v in record.items() if k != "dt"})
    with pytest.raises(TypeError, match="rpm"):
        ScaledScene.from_dict({k: v for k, v in record.items() if k != "rpm"})
    with pytest.raises(TypeError, match="surprise"):
        ScaledScene.from_dict({**record, "surprise": 1})
