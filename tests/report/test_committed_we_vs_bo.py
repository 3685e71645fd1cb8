"""docs/results/we_vs_bo (We vs Bo with a CG1 noise floor, 2026-11-28): its README is the
text scripts/kept_results.py renders from the committed report, analysis and controls
tables, and the conclusions its prose draws hold on those tables."""

from __future__ import annotations

import pandas as pd

from scripts.kept_results import WE_VS_BO, main


def test_readme_is_what_the_tables_say():
    assert main(["--check"]) == 0
    assert WE_VS_BO.check() == []


def test_the_conclusions_hold_on_the_conditions_table():
    c = pd.read_csv(WE_VS_BO.path / "conditions.csv")
    cgn = c[c["cg"] > 1]
    bond, weber = cgn[cgn["rule"] == "bond"], cgn[cgn["rule"] == "weber"]
    # every CG error is beyond the CG1-vs-CG1 floor, Weber's too
    assert set(cgn["angle_error_vs_floor"]) == set(cgn["profile_error_vs_floor"]) == {"beyond"}
    # Bond beds turn as a rigid block, CG1 and Weber never; the shares' intervals are disjoint
    assert (bond["rigid_frame_share_lo"] > 0).all()
    assert (c[c["rule"] != "bond"]["rigid_frame_share_hi"] == 0).all()
    # Bond's errors are larger than Weber's at each level, and Weber's grow with the level
    for level in (2.0, 3.0):
        b, w = bond[bond["cg"] == level].iloc[0], weber[weber["cg"] == level].iloc[0]
        assert b["angle_error"] > w["angle_error"] and b["profile_error"] > w["profile_error"]
        assert b["gsd_error_below"] > w["gsd_error_below"]
    assert weber["angle_error"].is_monotonic_increasing
    # We-CG2's intervals reach inside the floor: "beyond" is a point estimate there
    w2 = weber[weber["cg"] == 2.0].iloc[0]
    assert w2["angle_error_lo"] < w2["angle_error_floor"]
    assert w2["profile_error_lo"] < w2["profile_error_floor"]
