"""ligwf.report.verdict on hand-made condition tables: pass, fail and undecided criteria,
the cheapest-level sentence, none meeting the budget (naming the criterion that fails
first), the GSD criterion gated by the granule controls, a missing field error, control
twins left out, the ``accept:`` block (validation, ``--set``), and the written records.

Each table is built so the expected state follows from the definition (module docstring
of ligwf.report.verdict): pass when hi <= budget, fail when lo > budget, else undecided.
"""

from __future__ import annotations

import json
import math

import pandas as pd
import pytest

from ligwf.errors import ConfigError
from ligwf.report.verdict import (FAIL, FAILS, MEETS, NOT_ASSESSED, NOT_MEASURED, PASS,
                                  UNDECIDED, Gate, decide, granule_gates)
from ligwf.report.verdict_records import read_verdict, write_verdict
from ligwf.report.verdict_text import verdict_renderables, verdict_section
from ligwf.scene.accept import AcceptSettings, build_accept_settings
from ligwf.scene.workflow import load_workflow
from ligwf.yamlio import read_yaml_mapping
from ligwf.study import layout
from tests.helpers import ROOT

DEMO = ROOT / "workflows" / "demo.yaml"
NAN = math.nan
GROUP = "{}"
CG1_ANGLE = 40.0   # deg: angle_error 0.025 is 1 deg


def cg1(group: str = GROUP, replicas: int = 2, **extra) -> dict:
    """A CG1 reference row: angle 40 deg, no rigid frames, a 10 mm flowing layer."""
    return {"group": group, "cg": 1.0, "rule": "none", "replicas": replicas,
            "speedup_core": 1.0, "speedup_core_lo": NAN, "speedup_core_hi": NAN,
            "angle_of_repose": CG1_ANGLE, "angle_of_repose_lo": 39.5,
            "angle_of_repose_hi": 40.5, "angle_of_repose_se": 0.2,
            "rigid_frame_share": 0.0, "rigid_frame_share_lo": 0.0, "rigid_frame_share_hi": 0.0,
            "rigid_frame_share_se": 0.0,
            "flowing_layer_thickness_mean": 0.010, "flowing_layer_thickness_mean_lo": 0.0098,
            "flowing_layer_thickness_mean_hi": 0.0102,
            "flowing_layer_thickness_mean_se": 0.0001, **extra}


def cgn(cg: float, rule: str, speedup: float, angle_error=(0.01, 0.0, 0.02),
        profile=(0.05, 0.02, 0.08), rigid=(0.0, 0.0, 0.02), layer=(0.0101, 0.0099, 0.0103),
        gsd=(0.1, 0.05, 0.15), group: str = GROUP, replicas: int = 2,
        angle_floor: float = 0.01, profile_floor: float = 0.05, **extra) -> dict:
    """A CG-n row; every criterion passes under the default budget unless changed."""
    row = {"group": group, "cg": cg, "rule": rule, "replicas": replicas,
           "speedup_core": speedup, "speedup_core_lo": 0.8 * speedup,
           "speedup_core_hi": 1.25 * speedup,
           "angle_error_floor": angle_floor,
           "angle_error_floor_source": "measured over 2 CG1 replicas",
           "profile_error_floor": profile_floor,
           "profile_error_floor_source": "measured over 2 CG1 replicas"}
    for col, band in (("angle_error", angle_error), ("profile_error", profile),
                      ("rigid_frame_share", rigid), ("flowing_layer_thickness_mean", layer),
                      ("gsd_error_all", gsd)):
        row[col], row[f"{col}_lo"], row[f"{col}_hi"] = band
        row[f"{col}_se"] = NAN
    return {**row, **extra}


def table(*rows: dict) -> pd.DataFrame:
    return pd.DataFrame(list(rows))


PASSING = Gate(True)


def states(verdict, name: str) -> dict[str, str]:
    cond = next(c for g in verdict.groups for c in g.conditions if c.name == name)
    return {r.name: r.state for r in cond.criteria}


def test_all_pass_and_the_cheapest_level_is_named():
    v = decide(table(cg1(), cgn(2, "weber", 8.0), cgn(3, "weber", 25.0),
                     cgn(2, "bond", 9.0)), AcceptSettings(), {GROUP: PASSING})
    (g,) = v.groups
    assert all(c.state == MEETS for c in g.conditions)
    assert g.cheapest == "cg3-weber"
    assert g.sentence.startswith("cg3-weber is the cheapest level that meets the budget: "
                                 "speedup 25 [20, 31.2]; continuum fields not measured")
    assert set(states(v, "cg3-weber").values()) == {PASS, NOT_MEASURED}   # no field_error


def test_angle_is_in_degrees_and_the_floor_widens_the_budget():
    # 0.05 relative of 40 deg = 2 deg [1.2, 2.8]: beyond 1 deg -> fail ...
    row = cgn(2, "weber", 8.0, angle_error=(0.05, 0.03, 0.07), angle_floor=0.01)
    c = decide(table(cg1(), row), AcceptSettings(), {GROUP: PASSING}).groups[0].conditions[0]
    angle = c.criteria[0]
    assert angle.name == "angle_deg" and angle.unit == "deg"
    assert (angle.value, angle.lo, angle.hi) == pytest.approx((2.0, 1.2, 2.8))
    assert angle.state == FAIL and angle.budget == 1.0 and angle.budget_source == "tolerance"
    # ... but within a CG1 floor of 0.08 (3.2 deg), which is larger than the tolerance
    row = cgn(2, "weber", 8.0, angle_error=(0.05, 0.03, 0.07), angle_floor=0.08)
    angle = decide(table(cg1(), row), AcceptSettings(), {GROUP: PASSING}
                   ).groups[0].conditions[0].criteria[0]
    assert angle.state == PASS and angle.budget == pytest.approx(3.2)
    assert angle.budget_source.startswith("CG1 noise floor (measured over 2")
    # --set accept.angle_deg=3 passes it at the tolerance too
    angle = decide(table(cg1(), cgn(2, "weber", 8.0, angle_error=(0.05, 0.03, 0.07))),
                   AcceptSettings(angle_deg=3.0), {GROUP: PASSING}).groups[0].conditions[0].criteria[0]
    assert angle.state == PASS and angle.budget == 3.0


def test_undecided_says_how_many_cg1_replicas_would_decide():
    # profile 0.12 [0.06, 0.18] against a budget of 0.10: the interval straddles it;
    # R0 (half / gap)^2 = 2 x (0.06 / 0.02)^2 = 18 CG1 replicas
    row = cgn(2, "bond", 9.0, profile=(0.12, 0.06, 0.18))
    v = decide(table(cg1(), row), AcceptSettings(), {GROUP: PASSING})
    c = v.groups[0].conditions[0]
    profile = next(r for r in c.criteria if r.name == "profile_error")
    assert profile.state == UNDECIDED and c.state == UNDECIDED
    assert profile.note == "about 18 CG1 replicas would decide"
    assert v.groups[0].cheapest is None
    assert v.groups[0].sentence.startswith("No CG level is shown to meet the whole budget: ")
    assert "cg2-bond is undecided on the velocity profile (the velocity profile: about 18 " \
        "CG1 replicas would decide)" in v.groups[0].sentence
    # a value within the budget whose interval crosses it is not a pass (nor is the angle:
    # 0.02 x 40 = 0.8 deg within 1 deg, but its interval reaches 1.6 deg)
    row = cgn(2, "bond", 9.0, profile=(0.08, 0.03, 0.14), angle_error=(0.02, 0.0, 0.04),
              angle_floor=0.0)
    st = states(decide(table(cg1(), row), AcceptSettings(), {GROUP: PASSING}), "cg2-bond")
    assert st["profile_error"] == UNDECIDED and st["angle_deg"] == UNDECIDED
    # 2 x (0.25 / 0.01)^2 = 1250 replicas: beyond what the verdict suggests
    row = cgn(2, "bond", 9.0, profile=(0.11, 0.0, 0.5))
    note = next(r.note for r in decide(table(cg1(), row), AcceptSettings(), {GROUP: PASSING}
                                       ).groups[0].conditions[0].criteria
                if r.name == "profile_error")
    assert note.startswith("over 64 CG1 replicas would be needed")
    # one CG-n replica: no interval, nothing decided
    one = cgn(2, "bond", 9.0, replicas=1, profile=(0.01, NAN, NAN))
    profile = next(r for r in decide(table(cg1(), one), AcceptSettings(), {GROUP: PASSING}
                                     ).groups[0].conditions[0].criteria if r.name == "profile_error")
    assert profile.state == UNDECIDED and "add CG-n replicas" in profile.note


def test_none_meets_the_budget_names_the_first_failing_criterion():
    # Bond: rigid frames 0.3 [0.2, 0.4] above CG1's 0 (budget 0.05) and the flowing layer
    # 40 % off; the rigid share comes first in the budget's order but after the angle,
    # which passes. Weber: the angle fails (3 deg [2, 4]) before anything else.
    bond = cgn(2, "bond", 9.0, rigid=(0.3, 0.2, 0.4), layer=(0.014, 0.0135, 0.0145))
    weber = cgn(2, "weber", 8.0, angle_error=(0.075, 0.05, 0.1),
                rigid=(0.3, 0.2, 0.4))
    v = decide(table(cg1(), bond, weber), AcceptSettings(), {GROUP: PASSING})
    (g,) = v.groups
    assert [c.state for c in g.conditions] == [FAILS, FAILS]
    assert g.cheapest is None
    assert g.sentence.startswith("No CG level meets the whole budget: cg2-bond fails the "
                                 "rigid-block frames first (0.3 [0.2, 0.4] > 0.05); cg2-weber "
                                 "fails the angle of repose first (3 [2, 4] deg > 1)")
    layer = states(v, "cg2-bond")["flowing_layer"]
    assert layer == FAIL     # |0.014 / 0.010 - 1| = 0.4, lo 0.0135 / 0.0102 - 1 = 0.32 > 0.15


def test_a_cheaper_undecided_level_is_mentioned_beside_the_one_that_meets():
    ok = cgn(2, "weber", 8.0)
    open_ = cgn(3, "weber", 25.0, profile=(0.12, 0.06, 0.18))
    g = decide(table(cg1(), ok, open_), AcceptSettings(), {GROUP: PASSING}).groups[0]
    assert g.cheapest == "cg2-weber"
    assert "cg3-weber (speedup 25 [20, 31.2]) might too: undecided on the velocity profile" \
        in g.sentence


def test_gsd_is_assessed_only_where_the_granules_beat_their_control():
    bad_gsd = cgn(2, "weber", 8.0, gsd=(0.9, 0.8, 1.0))
    rows = table(cg1(), bad_gsd)
    assert states(decide(rows, AcceptSettings(), {GROUP: PASSING}), "cg2-weber")["gsd_error"] == FAIL
    failed = Gate(False, "granules did not beat their cohesionless control")
    v = decide(rows, AcceptSettings(), {GROUP: failed})
    c = v.groups[0].conditions[0]
    gsd = next(r for r in c.criteria if r.name == "gsd_error")
    assert gsd.state == NOT_ASSESSED
    assert gsd.note == "not assessed: granules did not beat their cohesionless control"
    assert c.state == MEETS   # the flow criteria all pass; the GSD is not held against it
    assert "GSD not assessed: granules did not beat" in v.groups[0].sentence
    # no control ran at all: not assessed either (default gate)
    assert states(decide(rows, AcceptSettings()), "cg2-weber")["gsd_error"] == NOT_ASSESSED


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
    rows = table(cg1(), cgn(2, "weber", 8.0))
    field = next(r for r in decide(rows, AcceptSettings(), {GROUP: PASSING}
                                   ).groups[0].conditions[0].criteria if r.name == "field_error")
    assert field.state == NOT_MEASURED and "field_error" in field.note
    rows = table(cg1(), cgn(2, "weber", 8.0, field_error=0.3, field_error_lo=0.25,
                            field_error_hi=0.35, field_error_floor=0.05))
    assert states(decide(rows, AcceptSettings(), {GROUP: PASSING}), "cg2-weber")["field_error"] == FAIL
    rows = table(cg1(), cgn(2, "weber", 8.0, field_error=0.3, field_error_lo=0.25,
                            field_error_hi=0.35, field_error_floor=0.4))   # within its floor
    assert states(decide(rows, AcceptSettings(), {GROUP: PASSING}), "cg2-weber")["field_error"] == PASS


def test_a_criterion_set_to_null_is_left_out_and_control_twins_are_no_candidates():
    control = '{"control": "cohesionless"}'
    rows = table(cg1(), cgn(2, "weber", 8.0, rigid=(0.3, 0.2, 0.4)), cg1(group=control))
    v = decide(rows, AcceptSettings(rigid_share=None), {GROUP: PASSING})
    assert [g.group for g in v.groups] == [GROUP]
    assert "rigid_share" not in states(v, "cg2-weber")
    assert v.groups[0].cheapest == "cg2-weber"


def test_a_relative_difference_to_a_cg1_value_of_zero_is_not_measured():
    ref = cg1(flowing_layer_thickness_mean=0.0, flowing_layer_thickness_mean_lo=0.0,
              flowing_layer_thickness_mean_hi=0.001)
    c = decide(table(ref, cgn(2, "weber", 8.0)), AcceptSettings(), {GROUP: PASSING}
               ).groups[0].conditions[0]
    layer = next(r for r in c.criteria if r.name == "flowing_layer")
    assert layer.state == NOT_MEASURED and "reaches 0" in layer.note


def test_groups_without_cg1_or_without_cg_levels_say_so():
    v = decide(table(cgn(2, "weber", 8.0), cg1(group='{"rpm": 20}')), AcceptSettings())
    by = {g.group: g.sentence for g in v.groups}
    assert by[GROUP].startswith("No CG1 case in this group")
    assert by['{"rpm": 20}'].startswith("Only CG1 ran")


def test_records_round_trip_and_renderings(tmp_path):
    v = decide(table(cg1(), cgn(2, "weber", 8.0), cgn(2, "bond", 9.0, rigid=(0.3, 0.2, 0.4))),
               AcceptSettings(), {GROUP: PASSING})
    write_verdict(v, tmp_path)
    back = read_verdict(tmp_path)
    assert back is not None and back.groups[0].sentence == v.groups[0].sentence
    assert [c.state for c in back.groups[0].conditions] == [c.state for c in v.groups[0].conditions]
    csv = pd.read_csv(tmp_path / layout.VERDICT_TABLE)
    assert set(csv["criterion"]) == {"angle_deg", "profile_error", "rigid_share",
                                     "flowing_layer", "gsd_error", "field_error"}
    bond_rigid = csv[(csv["rule"] == "bond") & (csv["criterion"] == "rigid_share")].iloc[0]
    assert bond_rigid["state"] == FAIL and bond_rigid["lo"] == pytest.approx(0.2)
    record = json.loads((tmp_path / layout.VERDICT_RECORD).read_text())   # strict JSON: no NaN
    assert record["accept"]["angle_deg"] == 1.0
    md = verdict_section(v)
    assert md.startswith("## Verdict") and v.groups[0].sentence in md
    assert "| fail 0.3 [0.2, 0.4] |" in md and "rigid-block frames (<= 0.05) |" in md
    assert "angle of repose (<= 1 deg) |" in md
    assert len(verdict_renderables(v)) >= 3
    assert read_verdict(tmp_path / "nowhere") is None
    # the budget reads in the block's order, also from the record (stored with sorted keys)
    line = verdict_section(back).splitlines()[2]
    assert line.index("angle of repose <= 1 deg") < line.index("velocity profile <= 0.1") \
        < line.index("rigid-block frames <= 0.05") < line.index("continuum fields")


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
