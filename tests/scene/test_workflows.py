"""Every shipped workflow validates, renders and passes the pre-flight check."""

from __future__ import annotations

import pytest

from ligwf.pipeline.prepare import render_workflow
from ligwf.scene.stability import REFUSED, preflight
from ligwf.scene.workflow import load_workflow

from helpers import ROOT

WORKFLOWS = sorted(p.name for p in (ROOT / "workflows").glob("*.yaml") if p.name != "stability.yaml")


@pytest.mark.parametrize("name", WORKFLOWS)
def test_shipped_workflow_renders_and_is_not_refused(name):
    wf = load_workflow(ROOT / "workflows" / name)
    rendered = render_workflow(wf)
    assert rendered
    for rc in rendered:
        verdicts = [f for f in preflight(rc.scaled, rc.case.case_id).findings if f.verdict == REFUSED]
        assert not verdicts, (rc.case.case_id, [f.message for f in verdicts])


def test_paper_scale_is_the_source_scene():
    wf = load_workflow(ROOT / "workflows" / "paper_scale.yaml")
    cases = {c.case_id: c.scaled() for c in wf.cases}
    cg1 = cases["cg1-none-r0"]
    assert cg1.particles.count == 360_000
    assert (cg1.drum.diameter, cg1.drum.length, cg1.drum.periodic) == (0.2, 0.06, True)
    assert (cg1.drum.lifter_count, cg1.drum.lifter_height) == (48, 0.001)
    assert cg1.particles.diameters == (0.001,)
    assert cases["cg3-bond-r0"].particles.count == round(360_000 / 27)
    assert {s.rule for s in cases.values()} == {"none", "weber", "bond"}


def test_we_vs_bo_runs_more_revolutions_at_coarse_levels():
    wf = load_workflow(ROOT / "workflows" / "we_vs_bo.yaml")
    by_id = {c.case_id: c.scaled() for c in wf.cases}
    rev = {cid: s.numerics.run_steps * s.numerics.dt / s.drum.rotation_period for cid, s in by_id.items()}
    assert rev["cg1-none-r0"] == pytest.approx(1.0, rel=1e-3)
    assert rev["cg1-none-r1"] == pytest.approx(1.0, rel=1e-3)        # the noise floor
    assert rev["cg3-bond-r2"] == pytest.approx(2.0, rel=1e-3)
    assert by_id["cg1-none-r0"].drum.length == by_id["cg3-weber-r0"].drum.length
    assert by_id["cg3-weber-r0"].drum.length / by_id["cg3-weber-r0"].d_max == pytest.approx(6.0)
