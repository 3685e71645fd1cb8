"""A sweep without CG1 is a study like any other (issue 44 item 2), on the real engine:
``ligwf study --until-decided`` of a tiny drum at CG2 and CG3 only judges each level
against the CG1 value extrapolated from them (verdict.json, extrapolation.csv, the
report's sections, open_study) and its round adds replicas instead of stopping with "no
planned way to decide"."""

from __future__ import annotations

import json

import pandas as pd
import pytest

import ligwf
from helpers import ROOT
from ligwf.cli.main import main

TINY = ROOT / "tests" / "workflows" / "tiny_study.yaml"
pytestmark = [pytest.mark.engine, pytest.mark.mpi, pytest.mark.slow]


def test_until_decided_without_cg1(engine, tmp_path):
    out = tmp_path / "nocg1"
    rc = main(["study", str(TINY), "--out", str(out), "--mesh-cache", str(tmp_path / "m"),
               "--set", "sweep.cg_levels=[2,3]", "--set", "sweep.replicas=2",
               "--set", "scene.drum.length=0.018", "--set", "sweep.rules=[weber]",
               "--no-snapshots", "--until-decided", "--max-looks", "2"])
    assert rc == 0
    verdict = json.loads((out / "report" / "verdict.json").read_text())
    group = verdict["groups"][0]
    assert group["sentence"].startswith("No CG1 ran: every level is judged against the CG1 "
                                        "value extrapolated")
    states = {(c["name"], r["name"]): r["state"] for c in group["conditions"]
              for r in c["criteria"]}
    assert {c for c, _ in states} == {"cg2-weber", "cg3-weber"}
    for norm in ("profile_error", "field_error"):
        assert states[("cg2-weber", norm)] == "not assessed"
    table = pd.read_csv(out / "report" / "extrapolation.csv")
    assert set(table["levels"]) == {"2 3"} and set(table["form"]) == {"unchecked"}
    summary = (out / "report" / "summary.md").read_text()
    assert "## Extrapolated CG1" in summary and "## Resolution and grains" in summary
    s = ligwf.open_study(out)
    assert len(s.extrapolation) == len(table)
    # the first look planned a round (replicas on the level judged), not "no planned way"
    looks = json.loads((out / "rounds.json").read_text())["looks"]
    assert looks[0].get("actions"), looks[0]
    assert not any("no planned way" in (lk.get("stop") or "") for lk in looks)
    assert (out / "cg2-weber-r2").is_dir()
