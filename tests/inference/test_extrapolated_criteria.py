"""The verdict against an extrapolated CG1 (ligwf.inference.extrapolated) on hand-made run
tables: a level on the line passes, a level off it fails after Holm, a curve is "does not
extrapolate", identical runs everywhere are not a zero-width pass, norms are not assessed."""

from __future__ import annotations

import numpy as np
import pandas as pd

from ligwf.inference.extrapolated import extrapolated_criteria
from ligwf.scene.accept import AcceptSettings

ACCEPT = AcceptSettings()


def runs(angles: dict[float, list[float]], share: float | None = 0.0) -> pd.DataFrame:
    rows = []
    for n, values in angles.items():
        for k, a in enumerate(values):
            rows.append(dict(case_id=f"cg{n:g}-weber-r{k}", cg=n, rule="weber",
                             angle_of_repose=a, rigid_frame_share=share,
                             flowing_layer_thickness_mean=0.01 * (1 + 0.01 * n)))
    return pd.DataFrame(rows)


def states(table: pd.DataFrame, cg: float, ratio: float = 1 / 200) -> dict[str, str]:
    return {r.name: r.state for r in extrapolated_criteria(ACCEPT, table, cg, ratio)}


def spread(m: float) -> list[float]:
    return list(m + np.array([-0.05, 0.0, 0.05]))


def test_flat_levels_pass_the_angle_and_norms_are_not_assessed():
    t = runs({4.0: spread(38.0), 6.0: spread(38.02), 8.0: spread(38.04)})
    s = states(t, 4.0)
    assert s["angle_deg"] == "pass"
    assert s["profile_error"] == s["field_error"] == s["gsd_error"] == "not assessed"


def test_a_steep_line_fails_the_angle_at_its_coarsest_level():
    t = runs({4.0: spread(40.0), 6.0: spread(43.0), 8.0: spread(46.0)})
    assert states(t, 8.0)["angle_deg"] == "fail"


def test_a_curve_does_not_extrapolate():
    t = runs({2.0: spread(46.0), 3.0: spread(47.5), 4.0: spread(47.7)})
    r = {c.name: c for c in extrapolated_criteria(ACCEPT, t, 2.0, 1 / 50)}
    assert r["angle_deg"].state == "not assessed"
    assert "does not extrapolate" in r["angle_deg"].note


def test_identical_runs_everywhere_are_not_a_zero_width_pass():
    t = runs({4.0: spread(38.0), 6.0: spread(38.02), 8.0: spread(38.04)}, share=0.0)
    r = {c.name: c for c in extrapolated_criteria(ACCEPT, t, 4.0, 1 / 200)}
    assert r["rigid_share"].state == "undecided"
    assert "no run-to-run variance" in r["rigid_share"].note
