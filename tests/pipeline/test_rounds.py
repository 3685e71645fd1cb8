"""ligwf.pipeline.rounds without the engine: what a look decides to do next on a written
(not run) study, the stops (decided, looks spent, the cap), the replicas a round adds
(new case folders with new seeds, indices after the workflow's), the extensions it writes
(idempotent, the scene hash untouched), and the rounds record."""

from __future__ import annotations

import dataclasses
import json
import math

import pytest

from ligwf.errors import ConfigError
from ligwf.pipeline.prepare import prepare_workflow, write
from ligwf.pipeline.rounds import (RoundPlan, added_cases, apply_extensions, plan_look,
                                   start_rounds)
from ligwf.inference.registry import CriterionResult
from ligwf.inference.verdict import ConditionVerdict, GroupVerdict, Verdict
from ligwf.study.case import CaseFolder
from ligwf.study.condition import Arm, Condition
from ligwf.study.rounds import (CAPPED, DECIDED, EXTEND, LOOKS_SPENT, REPLICAS, STUCK,
                                AddReplicas, ExtendProduction, Look, Rounds, read_rounds,
                                write_rounds)
from ligwf.study.study import Study

from helpers import ROOT

WORKFLOW = ROOT / "tests" / "workflows" / "rounds_tiny.yaml"


@pytest.fixture
def study(tmp_path):
    prepared = prepare_workflow(WORKFLOW)
    return prepared, write(prepared, tmp_path / "study", tmp_path / "meshes")


def angle(state: str, **decide) -> CriterionResult:
    return CriterionResult("angle_deg", "angle of repose", "deg", state, 1.2, 0.4, 2.0, 1.0,
                           "tolerance", "", 2.0, **decide)


def verdict(*criteria: CriterionResult, speedup: float = 9.0) -> Verdict:
    cond = ConditionVerdict("{}", 1.5, "weber", 2, speedup, math.nan, math.nan, criteria)
    return Verdict((GroupVerdict("{}", (cond,), "sentence"),), {"angle_deg": 1.0})


def test_an_undecided_extension_becomes_the_next_round(study):
    prepared, s = study
    rounds = start_rounds(s.path, RoundPlan(3, None))
    look = plan_look(verdict(angle("undecided", round_by=EXTEND, round_arm="CG-n",
                                   round_amount=0.05)), s, rounds, 1)
    assert not look.stop and look.target == "cg1.5-weber" and look.alpha == pytest.approx(0.05 / 3)
    (act,) = look.actions
    dt = s.cases[2].scaled.numerics.dt
    assert isinstance(act, ExtendProduction) and act.arm == Arm.CG_N
    assert act.case_ids == ("cg1.5-weber-r0", "cg1.5-weber-r1")
    want = s.cases[2].scaled.numerics.run_steps + math.ceil(0.05 / dt)
    assert act.run_steps == {"cg1.5-weber-r0": want, "cg1.5-weber-r1": want}
    assert look.planned_core_hours > 0
    # applied: the case runs longer, its scene (and hash) is the rendered one
    rounds = rounds.with_look(look)
    apply_extensions(s, rounds)
    apply_extensions(Study.open(s.path), rounds)      # again: nothing changes
    case = CaseFolder.open(s.path / "cg1.5-weber-r0")
    assert case.scaled.numerics.run_steps == want
    assert case.extension_steps == want - s.cases[2].scaled.numerics.run_steps
    assert case.rendered_scaled == s.cases[2].scaled and case.scene_hash == s.cases[2].scene_hash
    assert case.record_problem() is None
    assert CaseFolder.open(s.path / "cg1-none-r0").extension_steps == 0


def test_replicas_are_new_cases_with_new_seeds_after_the_workflows(study, tmp_path):
    prepared, s = study
    look = plan_look(verdict(angle("undecided", round_by=REPLICAS, round_arm="CG-n and CG1",
                                   round_amount=2, round_amount_cg1=1)), s,
                     start_rounds(s.path, RoundPlan(3, None)), 1)
    kinds = {(type(a), a.arm): a for a in look.actions}
    assert kinds[(AddReplicas, Arm.CG_N)].replicas == (2, 3)
    assert kinds[(AddReplicas, Arm.CG1)].replicas == (2,)
    assert kinds[(AddReplicas, Arm.CG1)].condition == Condition("{}", 1.0, "none")
    more = added_cases(prepared, Rounds(3, looks=(look,)))
    new = more.rendered[len(prepared.rendered):]
    assert [rc.case.case_id for rc in new] == ["cg1.5-weber-r2", "cg1.5-weber-r3", "cg1-none-r2"]
    assert [rc.case.index for rc in new] == [4, 5, 6]
    for cg in (1.0, 1.5):                                # every replica its own seeds
        arm = [rc.scaled.fill.seeds for rc in more.rendered if rc.case.cg == cg]
        assert len(set(arm)) == len(arm) == (3 if cg == 1.0 else 4)
    s2 = write(more, s.path, tmp_path / "meshes")
    assert len(s2.cases) == 7 and s2.cases[6].case_id == "cg1-none-r2"


def test_stops_when_decided_when_the_looks_are_spent_and_at_the_cap(study):
    _, s = study
    rounds = start_rounds(s.path, RoundPlan(2, 1e-9))
    assert plan_look(verdict(angle("pass")), s, rounds, 1).stop.startswith("decided")
    open_ = verdict(angle("undecided", round_by=REPLICAS, round_arm="CG-n", round_amount=1))
    assert "looks are spent" in plan_look(open_, s, rounds, 2).stop
    assert "cap of 1e-09 core-h cannot decide" in plan_look(open_, s, rounds, 1).stop
    stuck = verdict(angle("undecided"))
    assert plan_look(stuck, s, rounds, 1).stop.startswith("no planned way to decide")
    kinds = [plan_look(v, s, rounds, n).stop_kind for v, n in
             ((verdict(angle("pass")), 1), (open_, 2), (open_, 1), (stuck, 1))]
    assert kinds == [DECIDED, LOOKS_SPENT, CAPPED, STUCK]


def test_a_raised_cap_continues_a_study_the_cap_stopped_and_a_lower_one_does_not(study):
    """The look the cap stopped is taken again with the new cap (same number: no extra look
    is spent, its data and level are unchanged); a cap still too low, or a study stopped
    for another reason, keeps its record."""
    _, s = study
    open_ = verdict(angle("undecided", round_by=REPLICAS, round_arm="CG-n", round_amount=1))
    rounds = start_rounds(s.path, RoundPlan(3, 1e-9))
    capped = plan_look(open_, s, rounds, 1)
    assert capped.stop_kind == CAPPED and "continues" in capped.stop
    write_rounds(s.path, rounds.with_look(capped))
    need = capped.core_hours + capped.planned_core_hours
    assert start_rounds(s.path, RoundPlan(3, 0.5 * need)).looks == (capped,)   # still short
    raised = start_rounds(s.path, RoundPlan(3, 2 * need))
    assert raised.looks == () and raised.max_core_hours == 2 * need
    again = plan_look(open_, s, raised, 1)
    assert again.number == 1 and not again.stop and again.actions
    write_rounds(s.path, raised.with_look(plan_look(verdict(angle("pass")), s, raised, 1)))
    assert len(start_rounds(s.path, RoundPlan(3, None)).looks) == 1        # decided: kept


def test_the_record_round_trips_and_its_looks_are_fixed(study):
    _, s = study
    rounds = start_rounds(s.path, RoundPlan(3, 2.5)).with_look(Look(1, 0.05 / 3, 0.1))
    write_rounds(s.path, rounds)
    back = read_rounds(s.path)
    assert back == rounds and back.alpha_per_look == pytest.approx(0.05 / 3)
    assert json.loads((s.path / "rounds.json").read_text())["method"].startswith("Bonferroni")
    with pytest.raises(ConfigError, match="--max-looks = 4: this study was started with 3"):
        start_rounds(s.path, RoundPlan(4, None))
    assert read_rounds(s.path / "nowhere").alpha_per_look == 0.05     # a study of one look


# ---------------------------------------------------------------- every level, stuck looks
@pytest.fixture
def two_rules(tmp_path):
    """rounds_tiny with both rules: two CG-n conditions sharing one CG1 arm."""
    import yaml
    raw = yaml.safe_load(WORKFLOW.read_text())
    raw["sweep"]["rules"] = ["weber", "bond"]
    path = tmp_path / "two_rules.yaml"
    path.write_text(yaml.safe_dump(raw))
    prepared = prepare_workflow(path)
    return prepared, write(prepared, tmp_path / "study2", tmp_path / "meshes")


def _cond(rule: str, speedup: float, *criteria: CriterionResult) -> ConditionVerdict:
    return ConditionVerdict("{}", 1.5, rule, 2, speedup, math.nan, math.nan, criteria)


def _levels(*conds: ConditionVerdict) -> Verdict:
    return Verdict((GroupVerdict("{}", conds, "sentence"),), {"angle_deg": 1.0})


def test_every_level_works_on_each_level_and_a_shared_cg1_arm_gets_the_most_asked(two_rules):
    """The default works on the cheapest level that can still pass (bond here: weber, the
    faster, fails); --every-level also on weber's undecided criterion, and the CG1 arm both
    ask replicas of gets the larger request (2), not the sum (3)."""
    _, s = two_rules
    fails = dataclasses.replace(angle("fail"), name="profile_error")
    weber = _cond("weber", 9.0, angle("undecided", round_by=REPLICAS, round_arm="CG1",
                                      round_amount=0, round_amount_cg1=1), fails)
    bond = _cond("bond", 5.0, angle("undecided", round_by=REPLICAS, round_arm="CG-n and CG1",
                                    round_amount=1, round_amount_cg1=2))
    v = _levels(weber, bond)
    cheapest = plan_look(v, s, start_rounds(s.path, RoundPlan(3, None)), 1)
    assert cheapest.target == "cg1.5-bond"
    every = plan_look(v, s, start_rounds(s.path, RoundPlan(3, None, every_level=True)), 1)
    assert every.target == "cg1.5-weber, cg1.5-bond"
    reps = {a.condition.name: a.replicas for a in every.actions if isinstance(a, AddReplicas)}
    assert reps == {"cg1": (2, 3), "cg1.5-bond": (2,)}
    assert read_rounds(s.path).every_level is True


def test_an_unplanned_criterion_does_not_hold_back_the_planned_ones(study):
    _, s = study
    v = verdict(angle("undecided", round_by=REPLICAS, round_arm="CG-n", round_amount=1),
                dataclasses.replace(angle("undecided"), name="rigid_share"))
    look = plan_look(v, s, start_rounds(s.path, RoundPlan(3, None)), 1)
    assert not look.stop and [a.replicas for a in look.actions] == [(2,)]


def test_a_stuck_look_is_taken_again_by_the_next_call(study):
    """Same number, same data, same level: the next call (e.g. with --every-level) may plan
    what the stuck look could not; a decided look stays."""
    _, s = study
    rounds = start_rounds(s.path, RoundPlan(3, None))
    stuck = plan_look(verdict(angle("undecided")), s, rounds, 1)
    assert stuck.stop_kind == STUCK
    write_rounds(s.path, rounds.with_look(stuck))
    again = start_rounds(s.path, RoundPlan(3, None, every_level=True))
    assert again.looks == () and again.every_level


def test_round_costs_are_calibrated_by_the_arms_fastest_run(study):
    """A round's planned core-hours scale the planner's rates by measured / planned of the
    arm's fastest finished run (a run slowed by a loaded machine does not inflate it)."""
    from ligwf.inference.planning import run_costs
    from ligwf.study.manifest import Manifest, write_manifest
    _, s = study
    v = verdict(angle("undecided", round_by=REPLICAS, round_arm="CG-n", round_amount=1))
    plain = plan_look(v, s, start_rounds(s.path, RoundPlan(3, None)), 1).planned_core_hours
    for case, factor in zip(s.cases[2:4], (3.0, 7.0)):
        planned = run_costs(case.scaled)[0]
        write_manifest(case.path, Manifest(case.case_id, case.index, case.scene_hash, "", "",
                                           status="done", core_seconds=factor * planned))
    s = Study.open(s.path)
    calibrated = plan_look(v, s, start_rounds(s.path, RoundPlan(3, None)), 1)
    assert calibrated.planned_core_hours == pytest.approx(3.0 * plain)


def test_added_replicas_are_the_cases_of_a_workflow_written_with_them(tmp_path):
    """The rounds add replicas through the typed workflow (Workflow.with_replicas), never
    by editing its YAML: each added case renders byte for byte as the same case of the
    workflow written with that many replicas (swept scene values, per-level settings,
    two rules, control twins around them), and the prepared workflow is left as written."""
    import copy

    import yaml
    from ligwf.pipeline.prepare import render_case
    from ligwf.scene.workflow import expand
    from ligwf.study.case import group_of
    raw = yaml.safe_load(WORKFLOW.read_text())
    raw["sweep"].update({"rules": ["weber", "bond"], "replicas": {1: 2, 1.5: 1},
                         "scene.process.rotation.rpm": [20, 30],
                         "per_cg": {1.5: {"process.run_time": 0.4}},
                         "controls": ["cohesionless"]})
    path = tmp_path / "rich.yaml"
    path.write_text(yaml.safe_dump(raw))
    prepared = prepare_workflow(path)
    group = group_of({"process.rotation.rpm": 30})
    look = Look(1, 0.05, 0.0, actions=(
        AddReplicas(Condition(group, 1.5, "bond"), (1, 2), 100),
        AddReplicas(Condition(group, 1.0, "none"), (2,), 100)))
    more = added_cases(prepared, Rounds(3, looks=(look,)))
    new = more.rendered[len(prepared.rendered):]
    assert [rc.case.case_id for rc in new] == ["cg1.5-bond-r1_rpm-30", "cg1.5-bond-r2_rpm-30",
                                               "cg1-none-r2_rpm-30"]
    assert [rc.case.index for rc in new] == list(range(len(prepared.rendered), len(more.rendered)))
    assert more.workflow is prepared.workflow and more.workflow.raw == raw
    written = copy.deepcopy(raw)
    written["sweep"]["replicas"] = {1: 3, 1.5: 3}
    same = {c.case_id: c for c in expand(written).cases}
    for rc in new:
        ref = render_case(same[rc.case.case_id])
        assert (rc.files, rc.mesh_text, rc.scene_hash) == (ref.files, ref.mesh_text,
                                                           ref.scene_hash)
    assert added_cases(more, Rounds(3, looks=(look,))).rendered == more.rendered   # idempotent


def _flow_with_windows(s, fractions: dict[str, float]) -> None:
    """The study's flow record as the analysis writes it, with an automatic steady window
    starting at ``fractions[case_id]`` of each case's production."""
    from ligwf.analysis.records.flow import CaseFlow, FlowRecord
    from ligwf.study import layout

    cases = {c.case_id: CaseFlow(c.case_id, c.cg, c.rule, c.replica, c.group,
                                 fractions[c.case_id], 0)
             for c in s.cases}
    s.analysis_dir.mkdir(parents=True, exist_ok=True)
    (s.analysis_dir / layout.FLOW_PROFILES).write_text(FlowRecord("auto", (), cases).to_text())


def too_short_verdict(state: str, note: str) -> Verdict:
    """A one-level verdict (every criterion ``state``) whose runs are flagged too short."""
    cond = ConditionVerdict("{}", 1.5, "weber", 2, 9.0, math.nan, math.nan, (angle(state),),
                            too_short=note)
    return Verdict((GroupVerdict("{}", (cond,), "sentence"),), {"angle_deg": 1.0})


@pytest.mark.parametrize("state", ["fail", "pass"])
def test_runs_too_short_are_extended_before_the_study_stops(study, state):
    """Issue 45 item 3: a level decided on runs whose steady windows start at their cap is
    not shown steady; the look extends exactly those runs' arms by the planner's rule (the
    most any capped run of the arm needs) instead of stopping, whatever the level's state."""
    from ligwf.analysis.records import steady_window

    _, s = study
    rounds = start_rounds(s.path, RoundPlan(3, None))
    flagged = too_short_verdict(state, "runs too short to show a steady state: ...")
    # no flow record yet: nothing to size the extension by, the study stops as decided
    assert plan_look(flagged, s, rounds, 1).stop_kind == DECIDED
    _flow_with_windows(s, {"cg1-none-r0": 0.1, "cg1-none-r1": 0.2,
                           "cg1.5-weber-r0": 0.47, "cg1.5-weber-r1": 0.3})
    look = plan_look(flagged, s, rounds, 1)
    assert not look.stop and "cg1.5-weber (runs too short)" in look.target
    (act,) = look.actions            # only the CG-n arm has a capped run
    base = s.cases[2].scaled
    production = base.numerics.run_steps * base.numerics.dt
    more = steady_window.least_extension(0.47, production)
    assert more == pytest.approx(2 * production)          # a capped run triples
    assert isinstance(act, ExtendProduction) and act.arm == Arm.CG_N
    assert act.seconds == pytest.approx(more)
    assert act.case_ids == ("cg1.5-weber-r0", "cg1.5-weber-r1")
    # the same verdict without the flag stops as before
    assert plan_look(too_short_verdict(state, ""), s, rounds, 1).stop_kind == DECIDED
    # the looks spent: it stops, naming the round it would have run
    last = plan_look(flagged, s, rounds, 3)
    assert last.stop_kind == LOOKS_SPENT and "runs too short" in last.stop


def test_a_capped_cg1_run_extends_the_cg1_arm(study):
    _, s = study
    rounds = start_rounds(s.path, RoundPlan(3, None))
    _flow_with_windows(s, {"cg1-none-r0": 0.49, "cg1-none-r1": 0.2,
                           "cg1.5-weber-r0": 0.1, "cg1.5-weber-r1": 0.1})
    look = plan_look(too_short_verdict("fail", "runs too short ..."), s, rounds, 1)
    (act,) = look.actions
    assert act.arm == Arm.CG1 and act.case_ids == ("cg1-none-r0", "cg1-none-r1")
