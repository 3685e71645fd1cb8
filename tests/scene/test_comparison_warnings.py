"""What a study can compare, said before it runs: no CG1 case, or one CG1 replica (an
indicative floor)."""

from __future__ import annotations

import copy

import yaml

from helpers import ROOT
from ligwf.scene.workflow import comparison_warnings, expand

GRANULES = yaml.safe_load((ROOT / "workflows" / "granules.yaml").read_text())


def warnings_for(**sweep) -> list[str]:
    raw = copy.deepcopy(GRANULES)
    raw["sweep"].update(sweep)
    return comparison_warnings(expand(raw))


def test_one_cg1_replica_warns_and_its_twin_does_not_count():
    """One CG1 replica (plus its cohesionless twin, which is not a replica)."""
    (w,) = warnings_for(replicas={1: 1, 2: 2})
    assert w.startswith("sweep.replicas = 1 at CG1") and "indicative" in w


def test_two_cg1_replicas_or_cg1_alone_do_not_warn():
    assert warnings_for() == []          # granules.yaml: 2 CG1 replicas
    assert warnings_for(replicas={1: 2, 2: 2}) == []
    assert warnings_for(cg_levels=[1], replicas=1, controls=[]) == []


def test_no_cg1_case_says_so_instead():
    (w,) = warnings_for(cg_levels=[2], replicas=2, controls=[])
    assert "no CG1 case" in w
