"""The condition (sweep group, CG level, rule) and its two arms as value types: names,
the CG1 reference a condition is compared with, which runs an arm holds, and the arms a
criterion's round_arm names."""

from __future__ import annotations

from types import SimpleNamespace

import pytest

from ligwf.study.condition import REFERENCE_CG, Arm, Condition

RPM = '{"process.rotation.rpm": 20}'


def test_names_and_the_reference():
    cond = Condition(RPM, 2.0, "weber")
    assert cond.name == "cg2-weber process.rotation.rpm=20" and cond.arm == Arm.CG_N
    assert cond.reference == Condition(RPM, REFERENCE_CG, "none") and cond.reference.name == \
        "cg1 process.rotation.rpm=20"
    assert cond.reference.is_reference and cond.reference.arm == Arm.CG1
    assert cond.side(Arm.CG_N) == cond and cond.side(Arm.CG1) == cond.reference
    assert Condition("{}", 1.5, "bond").name == "cg1.5-bond"
    control = Condition('{"control": "cohesionless"}', 1.0, "none")
    assert control.name == "cg1 cohesionless control"


def run(group: str, cg: float, rule: str) -> SimpleNamespace:
    return SimpleNamespace(group=group, cg=cg, rule=rule)


def test_which_runs_an_arm_covers():
    weber = Condition(RPM, 2.0, "weber")
    assert weber.covers(run(RPM, 2.0, "weber")) and not weber.covers(run(RPM, 2.0, "bond"))
    assert not weber.covers(run("{}", 2.0, "weber"))
    assert weber.reference.covers(run(RPM, 1.0, "none"))
    assert weber.reference.covers(run(RPM, 1.0, "weber"))      # a CG1 run, whatever rule
    assert Condition.of(run(RPM, 2.0, "weber")) == weber


@pytest.mark.parametrize("text, arms", [("CG-n", (Arm.CG_N,)), ("CG1", (Arm.CG1,)),
                                        ("CG-n and CG1", (Arm.CG_N, Arm.CG1)),
                                        ("CG1 and CG-n", (Arm.CG_N, Arm.CG1)), ("", ())])
def test_the_arms_a_criterion_names(text, arms):
    assert Arm.named_in(text) == arms
