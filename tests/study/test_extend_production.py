"""``ligwf run --extend-production S``: every case's production S seconds longer than
rendered, continued from its restarts, never twice and never shorter than a round made it
(:func:`ligwf.study.extension.extend_production`)."""

from __future__ import annotations

import math

from ligwf.cli.main import main
from ligwf.pipeline.prepare import prepare_workflow, write
from ligwf.study.case import CaseFolder
from ligwf.study.extension import extend_production, write_extension
from ligwf.study.study import Study

from helpers import ROOT

WORKFLOW = ROOT / "tests" / "workflows" / "rounds_tiny.yaml"


def test_every_case_runs_longer_once_and_a_longer_round_is_kept(tmp_path):
    s = write(prepare_workflow(WORKFLOW), tmp_path / "study", tmp_path / "meshes")
    first, other = s.cases[0], s.cases[1]
    dt, rendered = first.scaled.numerics.dt, first.scaled.numerics.run_steps
    # a round already took the second case further than the call asks
    write_extension(other.path, other.scaled.numerics.run_steps,
                    other.scaled.numerics.run_steps + 10 ** 6, other.scaled.numerics.dt)
    lines = extend_production(Study.open(s.path).cases, 0.01)
    assert len(lines) == len(s.cases) - 1 and not any(other.path.name + ":" in x for x in lines)
    case = CaseFolder.open(first.path)
    assert case.scaled.numerics.run_steps == rendered + math.ceil(0.01 / dt)
    assert case.rendered_scaled == first.scaled and case.record_problem() is None
    assert CaseFolder.open(other.path).extension_steps == 10 ** 6
    # the same call again: nothing written
    assert extend_production(Study.open(s.path).cases, 0.01) == []
    # a longer one: from the rendered production, not on top of the earlier extension
    extend_production(Study.open(s.path).cases, 0.02)
    assert CaseFolder.open(first.path).extension_steps == math.ceil(0.02 / dt)


def test_absurd_values_and_rounds_are_refused_in_one_line(tmp_path, capsys):
    for extra, field in ((["--extend-production", "-1"], "allowed range [0, 10000] s"),
                         (["--extend-production", "nan"], "allowed range [0, 10000] s"),
                         (["--extend-production", "1", "--until-decided"],
                          "--extend-production = 1: not with --until-decided")):
        cmd = "study" if "--until-decided" in extra else "run"
        assert main([cmd, str(WORKFLOW), "--out", str(tmp_path / "s"), *extra]) == 2
        err = capsys.readouterr().err
        assert field in err and len(err.strip().splitlines()) == 1, err
        assert not (tmp_path / "s").exists()
