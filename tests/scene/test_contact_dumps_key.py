"""Settings under an old name: read as the new one, with one warning naming both."""

from __future__ import annotations

import pytest

from ligwf.errors import ConfigError
from ligwf.pipeline.prepare import prepare, render_case
from ligwf.scene.renamed import renamed_setting_warnings
from ligwf.scene.workflow import apply_override, expand, load_workflow
from ligwf.yamlio import read_yaml_mapping

from helpers import DRUM

ONE_CASE = ["sweep.cg_levels=[2]", "sweep.rules=[bond]"]


def old_spelling(where: str):
    """tests/workflows/drum.yaml (one case) with its contact-dump switch, off, under the
    old name ``granules``: in the scene block, or swept."""
    raw = read_yaml_mapping(DRUM, "workflow file")
    raw["sweep"].update(cg_levels=[2], rules=["bond"])
    del raw["scene"]["analysis"]["contact_dumps"]
    if where == "scene":
        apply_override(raw, "scene.analysis.granules", False)
    else:
        raw["sweep"]["scene.analysis.granules"] = [False]
    return expand(raw)


@pytest.mark.parametrize("where", ["scene", "sweep"])
def test_the_old_contact_dump_key_renders_the_same_case_and_is_warned(where):
    new = load_workflow(DRUM, ONE_CASE + ["scene.analysis.contact_dumps=false"])
    wf = old_spelling(where)
    assert render_case(wf.cases[0]).scene_hash == render_case(new.cases[0]).scene_hash
    assert not wf.cases[0].scaled().contact_dumps
    warned = [w for w in prepare(wf).warnings if "renamed" in w]
    assert len(warned) == 1
    assert "analysis.granules" in warned[0] and "analysis.contact_dumps" in warned[0]
    assert renamed_setting_warnings(new) == []


def test_both_names_at_once_are_refused_naming_both():
    with pytest.raises(ConfigError, match="analysis.granules and analysis.contact_dumps"):
        load_workflow(DRUM, ["scene.analysis.granules=true", "scene.analysis.contact_dumps=true"])
