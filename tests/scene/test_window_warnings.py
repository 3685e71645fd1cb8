"""The held-granule window warning: production - steady start - hold_time - T/4 must leave
the survival measure frames (the gsd_cg study's lost measure, said before the run)."""

from __future__ import annotations

import copy
import math

import pytest
import yaml

from helpers import ROOT
from ligwf.scene.window import (MIN_USABLE_FRAMES, held_window_warnings, plug_arc,
                                plug_residence)
from ligwf.scene.workflow import expand

GRANULES = yaml.safe_load((ROOT / "workflows" / "granules.yaml").read_text())


def warnings_for(run_time: float, **analysis) -> list[str]:
    raw = copy.deepcopy(GRANULES)
    raw["scene"]["process"]["run_time"] = run_time
    raw["analysis"].update(analysis)
    return held_window_warnings(expand(raw))


def test_granules_timing_warns_once_naming_the_fields_and_the_run_time_that_fits():
    """The granules workflow (the former demo): 30 rpm (T = 2 s), 1 s hold, dumps every
    0.05 s, 2.5 s production: an auto window starting at 1.25 s leaves 1.25 - 1 - 0.5 < 0 s."""
    (w,) = warnings_for(2.5)
    assert w.startswith("analysis.hold_time = 1 s") and "process.run_time = 2.5 s" in w
    assert "0 of the 10" in w
    need = float(w.split("at least ")[1].split(" s")[0])
    assert need == pytest.approx((1.0 + 0.5 + MIN_USABLE_FRAMES * 0.05) / 0.5, rel=1e-3)
    assert warnings_for(need * 1.01) == []          # the suggested run time is enough


def test_fixed_steady_fraction_is_used_instead_of_the_latest_auto_start():
    assert warnings_for(2.5, steady_after=0.1) == []      # 2.25 - 1.5 = 0.75 s: 15 frames
    (w,) = warnings_for(2.5, steady_after=0.3)            # 1.75 - 1.5 = 0.25 s: 5 frames
    assert "steady_after = 0.3" in w and "5 of the 10" in w


def test_other_definitions_and_dry_scenes_do_not_warn():
    assert warnings_for(2.5, granules="communities") == []
    raw = copy.deepcopy(GRANULES)
    raw["scene"]["liquid"] = {"model": "none"}
    raw["scene"]["analysis"] = {"contact_dumps": False}
    raw["sweep"].update(controls=[], rules=["weber"])
    assert held_window_warnings(expand(raw)) == []


def test_a_hold_time_shorter_than_this_drums_plug_is_named():
    """The granules workflow's 0.3 fill covers 143 deg of shell: 0.8 s in the plug at 30 rpm (T = 2 s), so
    its 1 s window (1.25x) is fine; at 6 rpm (T = 10 s) the plug lasts 3.96 s and a 1 s window
    would count it as granules: the warning gives the plug, the arc and the value to use."""
    assert warnings_for(5.0) == []
    raw = copy.deepcopy(GRANULES)
    raw["scene"]["process"]["run_time"] = 30.0
    raw["scene"]["process"]["rotation"] = {"rpm": 6}
    (w,) = held_window_warnings(expand(raw))
    assert w.startswith("analysis.hold_time = 1 s: the co-rotating plug holds its bridges for 3.96 s")
    assert "143 deg of shell at fill 0.3" in w and "analysis.hold_time = 4.96 s" in w
    assert "4.96-10 s" in w
    raw["analysis"]["hold_time"] = 5.0
    assert held_window_warnings(expand(raw)) == []
    raw["analysis"]["hold_time"] = 12.0
    (w,) = held_window_warnings(expand(raw))
    assert "more than 1 revolution" in w


def test_plug_arc_is_the_circular_segment_of_the_fill():
    assert plug_arc(0.5) == pytest.approx(math.pi)
    theta = plug_arc(0.3)
    assert (theta - math.sin(theta)) / (2 * math.pi) == pytest.approx(0.3)
    assert plug_residence(0.5, 2.0) == pytest.approx(1.0)
    with pytest.raises(ValueError, match="fill_fraction"):
        plug_arc(1.2)
