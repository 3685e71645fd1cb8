"""ligwf.api.report_compare: two reports of the same runs side by side, on tables whose
answer is known, and the wall time of a real /usr/bin/time -v report."""

from __future__ import annotations

import math

import pandas as pd
import pytest

from ligwf.api.report_compare import beside, changed, decided, repeated_runs, wall_minutes


def _verdict(states: list[str], notes: list) -> pd.DataFrame:
    return pd.DataFrame({"condition": ["cg2-weber", "cg2-weber", "cg2-bond"],
                         "criterion": ["angle_deg", "field_error", "angle_deg"],
                         "state": states, "note": notes})


def test_decided_counts_pass_and_fail_on_the_criteria_named():
    v = _verdict(["pass", "fail", "undecided"], [None, None, None])
    assert decided(v, ["angle_deg"]) == (1, 2)
    assert decided(v, ["angle_deg", "field_error"]) == (2, 3)
    assert decided(v, []) == (0, 0)


def test_changed_rows_by_condition_and_criterion_missing_notes_equal():
    before = _verdict(["pass", "fail", "undecided"], [None, None, "about 8 replicas"])
    after = _verdict(["pass", "undecided", "undecided"], [None, None, "about 6 replicas"])
    assert len(beside(before, after)) == 3
    states = changed(before, after, "state")
    assert list(zip(states["condition"], states["criterion"], states["state_new"])) == [
        ("cg2-weber", "field_error", "undecided")]
    notes = changed(before, after, "note")           # two empty notes are no change
    assert list(notes["note_new"]) == ["about 6 replicas"]
    assert changed(before, before, "note").empty


def test_repeated_runs_match_by_seed_and_compare_every_digit():
    now = pd.DataFrame({"cg": [1.0, 2.0, 2.0], "rule": ["none", "weber", "weber"],
                        "replica": [0, 0, 1], "angle_of_repose": [40.0, 41.5, 39.0]})
    then = pd.DataFrame({"cg": [1.0, 2.0], "rule": ["none", "weber"], "replica": [0, 1],
                         "angle_of_repose": [40.0, 39.0 + 1e-12]})
    both = repeated_runs(now, then, "angle_of_repose")
    assert len(both) == 2                                     # cg2 r0 ran only now
    assert list(both["same"]) == [True, False]


def test_wall_minutes_reads_the_elapsed_line():
    report = ('\tCommand being timed: "ligwf study workflows/ladder.yaml"\n'
              "\tUser time (seconds): 9100.31\n"
              "\tElapsed (wall clock) time (h:mm:ss or m:ss): 1:18:30\n")
    assert math.isclose(wall_minutes(report), 78.5)
    assert math.isclose(wall_minutes(report.replace("1:18:30", "2:03.60")), 2.06)
    with pytest.raises(ValueError, match="Elapsed"):
        wall_minutes("\tUser time (seconds): 1.0\n")
