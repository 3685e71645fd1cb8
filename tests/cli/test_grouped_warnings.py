"""ligwf check prints a warning that differs only in the case it names once, with the cases
listed (issue 33: a 5-seed study printed the same cohesion warning five times)."""

from __future__ import annotations

from ligwf.cli.common import grouped_warnings

IDS = ["cg1-none-r0", "cg1-none-r1", "cg1-none-r10", "cg1-none-r2", "cg1-none-r3"]


def test_the_same_warning_for_several_cases_is_one_line():
    lines = [f"{c}: liquid.surface_tension: too strong" for c in IDS] + ["a study warning"]
    out = grouped_warnings(lines, IDS)
    assert out == ["cg1-none-r0, cg1-none-r1, cg1-none-r10, cg1-none-r2, ... (5 cases): "
                   "liquid.surface_tension: too strong", "a study warning"]


def test_different_warnings_and_the_case_named_mid_line_stay_apart():
    lines = ["x (cg1-none-r1) is odd", "x (cg1-none-r10) is odd", "cg1-none-r0: y"]
    assert grouped_warnings(lines, IDS) == ["x (cg1-none-r1, cg1-none-r10) is odd",
                                            "cg1-none-r0: y"]
    assert grouped_warnings(["no case here"], []) == ["no case here"]
