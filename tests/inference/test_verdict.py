"""ligwf.inference.verdict on hand-made run tables: signed criteria decided by two one-sided
tests on the difference of run means (pass inside +-budget, fail wholly outside, else
undecided with the arm whose replicas would decide), the noise-corrected profile distance,
Holm over a level's fail tests, the bound each level is shown to stay within, the
cheapest-level sentence, the GSD gated by the granule controls, control twins left out,
the ``accept:`` block (validation, ``--set``) and the written records.

The runs are chosen so the expected state follows from the arithmetic of Welch's interval
(checked against scipy's own Welch test in tests/inference/test_equivalence.py).
"""

from __future__ import annotations

import json
import math

import numpy as np
import pandas as pd
import pytest

from ligwf.errors import ConfigError
from ligwf.inference.equivalence import FAIL, PASS, UNDECIDED
from ligwf.inference.registry import NOT_ASSESSED, NOT_MEASURED, Gate
from ligwf.inference.verdict import FAILS, MEETS, decide, granule_gates
from ligwf.inference.verdict_records import read_verdict, write_verdict
from ligwf.report.verdict_text import verdict_renderables, verdict_section
from ligwf.scene.accept import AcceptSettings, build_accept_settings
from ligwf.scene.workflow import load_workflow
from ligwf.yamlio import read_yaml_mapping
from ligwf.study import layout
from ligwf.study.condition import Condition
from tests.helpers import ROOT

DEMO = ROOT / "workflows" / "demo.yaml"
NAN = math.nan
GROUP = "{}"
PASSING = Gate(True)
PROFILE = np.array([0.10, 0.08, 0.05, 0.02])   # m/s, a downhill velocity profile


def runs(cg: float, rule: str, angles, rigid=None, layer=None, group: str = GROUP,
         profile_shift: float = 0.0) -> list[dict]:
    """One case row per angle (deg); rigid shares and flowing layers default to CG1's (a
    share that is not 0 in every run: an all-zero arm is bounded over its runs only)."""
    n = len(angles)
    rigid = rigid if rigid is not None else [0.010 + 0.001 * k for k in range(n)]
    layer = layer if layer is not None else [0.0100 + 0.0001 * k for k in range(n)]
    return [{"case_id": f"cg{cg:g}-{rule}-r{k}-{group}", "group": group, "cg": float(cg),
             "rule": rule, "replica": k, "angle_of_repose": angles[k],
             "rigid_frame_share": rigid[k], "flowing_layer_thickness_mean": layer[k],
             "_shift": profile_shift} for k in range(n)]


def study(*arms: list[dict], speedups: dict | None = None, extra: dict | None = None):
    """(conditions, cases, profiles) of the arms: one condition row per (group, cg, rule)."""
    cases = pd.DataFrame([r for arm in arms for r in arm])
    speedups = speedups or {}
    rows = []
    for (group, cg, rule), sub in cases.groupby(["group", "cg", "rule"], sort=False):
        sp = speedups.get((cg, rule), 1.0 if cg == 1 else 8.0 * cg)
        rows.append({"group": group, "cg": cg, "rule": rule, "replicas": len(sub),
                     "speedup_core": sp, "speedup_core_lo": 0.9 * sp,
                     "speedup_core_hi": 1.1 * sp, **(extra or {}).get((cg, rule), {})})
    profiles = {r["case_id"]: list(PROFILE * (1 + r["_shift"]) + 0.001 * r["replica"])
                for _, r in cases.iterrows()}
    return pd.DataFrame(rows), cases.drop(columns="_shift"), profiles


def verdict(*arms, accept=None, gates=None, **kw):
    conditions, cases, profiles = study(*arms, **kw)
    return decide(conditions, accept or AcceptSettings(), gates or {GROUP: PASSING}, cases,
                  profiles)


def crit(v, name: str):
    cond = next(c for g in v.groups for c in g.conditions if c.name == name)
    return {r.name: r for r in cond.criteria}


CG1 = runs(1, "none", [40.0, 40.2, 39.8])


def test_all_pass_and_the_cheapest_level_is_named():
    v = verdict(CG1, runs(2, "weber", [40.1, 39.9, 40.0]), runs(3, "weber", [40.0, 40.2, 39.9]))
    (g,) = v.groups
    assert [c.state for c in g.conditions] == [MEETS, MEETS]
    assert g.cheapest == "cg3-weber"
    assert g.sentence.startswith("cg3-weber is the cheapest level that meets the budget: "
                                 "speedup 24 [21.6, 26.4]")
    angle = crit(v, "cg3-weber")["angle_deg"]
    # Welch: d = 0.0333, se = sqrt(0.0233/3 + 0.04/3) = 0.1453, df = 3.7, t_0.95 = 2.19
    assert angle.value == pytest.approx(0.0333, abs=1e-3)
    assert angle.hi - angle.lo == pytest.approx(2 * 0.1453 * 2.19, rel=0.03)
    assert angle.bound == pytest.approx(max(abs(angle.lo), abs(angle.hi)))
    assert angle.budget == 1.0 and angle.budget_source == "tolerance"


def test_signed_difference_fails_wholly_outside_and_is_undecided_across_the_budget():
    v = verdict(CG1, runs(2, "weber", [42.0, 42.2, 41.9]),     # +2 deg, tight: fail
                runs(3, "weber", [41.5, 39.5, 43.5]))          # +1.5 deg, wide: undecided
    assert crit(v, "cg2-weber")["angle_deg"].state == FAIL
    assert crit(v, "cg2-weber")["angle_deg"].lo > 1.0
    u = crit(v, "cg3-weber")["angle_deg"]
    assert u.state == UNDECIDED and "more CG-n replicas" in u.note
    assert u.decide_by == "replicas" and u.decide_amount > max(3, u.decide_amount_cg1)
    # the sign is kept: a CG-n bed 2 deg below CG1 fails too (no folding)
    low = crit(verdict(CG1, runs(2, "weber", [38.0, 38.2, 37.9])), "cg2-weber")["angle_deg"]
    assert low.state == FAIL and low.hi < -1.0 and low.value < 0
    assert v.groups[0].sentence.startswith("No CG level is shown to meet the whole budget")
    assert "cg2-weber fails the angle of repose first (2.03 [1.72, 2.35] deg beyond the budget 1)" \
        in v.groups[0].sentence


def test_one_run_arm_has_no_interval_and_says_so():
    v = verdict(runs(1, "none", [40.0]), runs(2, "weber", [40.1, 39.9]))
    a = crit(v, "cg2-weber")["angle_deg"]
    assert a.state == UNDECIDED and "CG1 has one run" in a.note and math.isnan(a.lo)


def test_the_noise_floor_is_a_statement_not_a_wider_budget():
    # CG1 noisy: a 1.5 deg mean offset stays undecided against 1 deg, never widened to pass
    noisy = runs(1, "none", [38.0, 42.0, 40.0])
    a = crit(verdict(noisy, runs(2, "weber", [41.5, 41.6, 41.4])), "cg2-weber")["angle_deg"]
    assert a.state == UNDECIDED and a.budget == 1.0
    assert "indistinguishable from CG1 seed noise" in a.note
    tight = crit(verdict(CG1, runs(2, "weber", [40.5, 40.6, 40.55])), "cg2-weber")["angle_deg"]
    assert tight.state == PASS and "differs from CG1 beyond seed noise" in tight.note


def test_rigid_block_share_of_bond_fails_and_holm_keeps_a_lone_marginal_fail_undecided():
    v = verdict(CG1, runs(2, "bond", [46.0, 47.0, 45.5], rigid=[0.30, 0.32, 0.29]))
    c = crit(v, "cg2-bond")
    assert c["rigid_share"].state == FAIL and c["angle_deg"].state == FAIL
    assert v.groups[0].conditions[0].state == FAILS
    # a fail whose one-sided p lies between alpha/m and alpha does not survive Holm
    marginal = runs(2, "weber", [41.45, 41.70, 41.20])   # lo just above 1 deg
    m = crit(verdict(CG1, marginal), "cg2-weber")["angle_deg"]
    assert m.lo > 1.0 and m.state == UNDECIDED and "not after Holm" in m.note
    # what would decide it is planned at Holm's alpha / m, where the fail does not hold yet:
    # a real amount (the demo once printed '3.4e-16 s more production'), whose predicted
    # half-width (at alpha / m) is narrower than the difference's distance from the budget
    assert m.decide_by and m.decide_amount >= 1, (m.decide_by, m.decide_amount)
    assert 0 < m.decide_half_width < m.value - 1.0


def test_profile_distance_is_noise_corrected_and_bounded():
    v = verdict(CG1, runs(2, "weber", [40.0, 40.1, 39.9]),
                runs(3, "weber", [40.0, 40.1, 39.9], profile_shift=0.5))
    same = crit(v, "cg2-weber")["profile_error"]
    assert same.state == PASS and same.value <= same.hi <= 0.10
    assert "raw distance" in same.note
    far = crit(v, "cg3-weber")["profile_error"]
    assert far.state == FAIL and far.lo > 0.10


def test_gsd_is_assessed_only_where_the_granules_beat_their_control():
    extra = {(2.0, "weber"): {"gsd_error_all": 0.9, "gsd_error_all_lo": 0.8,
                              "gsd_error_all_hi": 1.0}}
    arms = (CG1, runs(2, "weber", [40.1, 39.9, 40.0]))
    assert crit(verdict(*arms, extra=extra), "cg2-weber")["gsd_error"].state == FAIL
    failed = Gate(False, "granules did not beat their cohesionless control")
    v = verdict(*arms, extra=extra, gates={GROUP: failed})
    gsd = crit(v, "cg2-weber")["gsd_error"]
    assert gsd.state == NOT_ASSESSED
    assert gsd.note == "not assessed: granules did not beat their cohesionless control"
    assert v.groups[0].conditions[0].state == MEETS
    assert "GSD not assessed: granules did not beat" in v.groups[0].sentence


def test_granule_gates_from_the_controls_table():
    cases = pd.DataFrame({"case_id": ["a", "b", "c"], "group": [GROUP, GROUP, '{"x": 1}']})
    controls = pd.DataFrame({"case_id": ["a", "a", "b"], "definition": ["own", "other", "own"],
                             "passes": [True, False, True]})
    gates = granule_gates(cases, controls)
    assert gates[GROUP].passes is True          # the first row per case is the own definition
    assert gates['{"x": 1}'].passes is None     # no twin in that group
    controls.loc[2, "passes"] = False
    assert granule_gates(cases, controls)[GROUP].passes is False
    assert granule_gates(cases, None)[GROUP].passes is None


def test_field_error_is_not_measured_without_its_column_and_decided_with_it():
    arms = (CG1, runs(2, "weber", [40.1, 39.9, 40.0]))
    f = crit(verdict(*arms), "cg2-weber")["field_error"]
    assert f.state == NOT_MEASURED and "field_error" in f.note
    extra = {(2.0, "weber"): {"field_error": 0.3, "field_error_lo": 0.25, "field_error_hi": 0.35,
                              "field_error_floor": 0.4}}
    # the floor (0.4) no longer widens the budget: 0.25 > 0.1 fails
    assert crit(verdict(*arms, extra=extra), "cg2-weber")["field_error"].state == FAIL


def test_a_criterion_set_to_null_is_left_out_and_control_twins_are_no_candidates():
    control = '{"control": "cohesionless"}'
    v = verdict(CG1, runs(2, "weber", [40.1, 39.9, 40.0], rigid=[0.3, 0.35, 0.32]),
                runs(1, "none", [32.0, 32.1], group=control),
                accept=AcceptSettings(rigid_share=None))
    assert [g.group for g in v.groups] == [GROUP]
    assert "rigid_share" not in crit(v, "cg2-weber")
    assert v.groups[0].cheapest == "cg2-weber"


def test_a_relative_difference_to_a_cg1_value_of_zero_is_not_measured():
    zero = runs(1, "none", [40.0, 40.2, 39.8], layer=[0.0, 0.0, 0.0])
    layer = crit(verdict(zero, runs(2, "weber", [40.1, 39.9, 40.0])), "cg2-weber")["flowing_layer"]
    assert layer.state == NOT_MEASURED and "is 0" in layer.note


def test_groups_without_cg1_or_without_cg_levels_say_so():
    v = verdict(runs(2, "weber", [40.1, 39.9]), runs(1, "none", [40.0, 40.1], group='{"rpm": 20}'))
    by = {g.group: g.sentence for g in v.groups}
    assert by[GROUP].startswith("No CG1 case in this group")
    assert by['{"rpm": 20}'].startswith("Only CG1 ran")


def test_records_round_trip_and_renderings(tmp_path):
    v = verdict(CG1, runs(2, "weber", [40.1, 39.9, 40.0]),
                runs(2, "bond", [46.0, 47.0, 45.5], rigid=[0.30, 0.32, 0.29]))
    write_verdict(v, tmp_path)
    back = read_verdict(tmp_path)
    assert back is not None and back.groups[0].sentence == v.groups[0].sentence
    assert [c.state for c in back.groups[0].conditions] == [c.state for c in v.groups[0].conditions]
    csv = pd.read_csv(tmp_path / layout.VERDICT_TABLE)
    assert set(csv["criterion"]) == {"angle_deg", "profile_error", "rigid_share",
                                     "flowing_layer", "gsd_error", "field_error"}
    bond_rigid = csv[(csv["rule"] == "bond") & (csv["criterion"] == "rigid_share")].iloc[0]
    assert bond_rigid["state"] == FAIL and bond_rigid["lo"] > 0.05
    assert bond_rigid["shown_within"] == pytest.approx(bond_rigid["hi"])
    record = json.loads((tmp_path / layout.VERDICT_RECORD).read_text())   # strict JSON: no NaN
    assert record["accept"]["angle_deg"] == 1.0
    md = verdict_section(v)
    assert md.startswith("## Verdict") and v.groups[0].sentence in md
    assert "rigid-block frames (+-0.05) |" in md and "angle of repose (+-1 deg) |" in md
    assert "velocity profile (<= 0.1) |" in md
    assert "Shown to stay within" in md and "**cg2-weber** (speedup 16): angle of repose" in md
    assert len(verdict_renderables(v)) >= 3
    assert read_verdict(tmp_path / "nowhere") is None
    line = verdict_section(back).splitlines()[2]
    assert line.index("angle of repose +-1 deg") < line.index("velocity profile <= 0.1") \
        < line.index("rigid-block frames +-0.05") < line.index("continuum fields")


# -- the accept: block ---------------------------------------------------------------------

def test_accept_block_validation_names_field_value_and_range():
    with pytest.raises(ConfigError, match=r"accept\.angle_deg = -1: .*allowed range \[0, 90\]"):
        build_accept_settings({"angle_deg": -1})
    with pytest.raises(ConfigError, match=r"accept\.rigid_share = 2: .*allowed range \[0, 1\]"):
        build_accept_settings({"rigid_share": 2})
    with pytest.raises(ConfigError, match=r"accept\.angel"):
        build_accept_settings({"angel": 1.0})
    with pytest.raises(ConfigError, match=r"accept\.profile_error = '0\.1'"):
        build_accept_settings({"profile_error": "0.1"})
    with pytest.raises(ConfigError, match=r"accept = 5: must be a mapping"):
        build_accept_settings(5)


def test_accept_through_the_workflow_and_set():
    wf = load_workflow(DEMO, ["accept.angle_deg=2", "accept.gsd_error=null"])
    assert wf.accept.angle_deg == 2.0 and wf.accept.gsd_error is None
    assert wf.accept.profile_error == AcceptSettings().profile_error
    with pytest.raises(ConfigError, match=r"accept\.angle_deg = 100: .*allowed range \[0, 90\]"):
        load_workflow(DEMO, ["accept.angle_deg=100"])
    raw = read_yaml_mapping(DEMO, "workflow")
    assert "accept" in raw, "workflows/demo.yaml shows its accept: block"
    assert load_workflow(DEMO).accept == AcceptSettings(), "the demo's block shows the defaults"


def test_report_set_re_decides_only_the_budget():
    from ligwf.pipeline.post import overridden_accept
    a = overridden_accept(AcceptSettings(), ("accept.angle_deg=3", "accept.gsd_error=null"))
    assert a.angle_deg == 3.0 and a.gsd_error is None and a.rigid_share == 0.05
    with pytest.raises(ConfigError, match=r"only re-decides the budget"):
        overridden_accept(AcceptSettings(), ("analysis.hold_time=2",))
    with pytest.raises(ConfigError, match=r"accept\.angle_deg = 100: .*allowed range \[0, 90\]"):
        overridden_accept(AcceptSettings(), ("accept.angle_deg=100",))
    # a wider budget turns the +2 deg fail into a pass, from the same runs
    arms = (CG1, runs(2, "weber", [42.0, 42.2, 41.9]))
    assert crit(verdict(*arms), "cg2-weber")["angle_deg"].state == FAIL
    assert crit(verdict(*arms, accept=a), "cg2-weber")["angle_deg"].state == PASS


def test_a_sweep_without_cg1_reports_the_speedup_of_its_condition():
    """The planner's CG1 speedups of a sweep without CG1 are keyed by Condition: each level
    reports its own, a level without one reports none."""
    arms = [runs(n, "weber", [40.0 + 0.3 * n + 0.1 * k for k in range(3)]) for n in (2, 3, 4)]
    conditions, cases, profiles = study(*arms)
    v = decide(conditions, AcceptSettings(), {GROUP: PASSING}, cases, profiles,
               size_ratio=0.01, speedups={Condition(GROUP, 2.0, "weber"): 7.5,
                                          Condition(GROUP, 3.0, "weber"): 20.0})
    got = {c.condition: c.speedup for c in v.groups[0].conditions}
    assert got[Condition(GROUP, 2.0, "weber")] == 7.5
    assert got[Condition(GROUP, 3.0, "weber")] == 20.0
    assert math.isnan(got[Condition(GROUP, 4.0, "weber")])
