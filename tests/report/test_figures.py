"""Report figures on hand-made tables: functions draw into an Axes and return it, run costs
are grouped bars (a small phase is as visible as a large one), legends sit below the data,
log axes carry several tick labels, the GSD axis is the equivalent diameter in mm with the
size limit marked, kinetics count time from production start, snapshots know which way
the drum turns; importing the report sets no matplotlib backend."""

from __future__ import annotations

import subprocess
import sys

import numpy as np
import pandas as pd
import pytest
from matplotlib.figure import Figure

from ligwf.report.figures import (equivalent_diameter_mm, error_ax, gsd_ax, pareto,
                                  run_cost_ax)
from ligwf.report.granule_figures import kinetics_ax, production_origins, sensitivity_ax
from ligwf.report.snapshots import SpeedScale, rotation_sense, snapshot_ax
from ligwf.scene.axis import Axis


def conditions() -> pd.DataFrame:
    return pd.DataFrame({
        "cg": [1.0, 2.0, 2.0], "rule": ["none", "weber", "bond"],
        "production_core_rate_k": [50.0, 8.0, 7.0],
        "angle_error": [np.nan, 0.03, 0.09], "angle_error_lo": [np.nan, 0.0, 0.0],
        "angle_error_hi": [np.nan, 0.08, 0.3], "angle_error_floor": [0.05] * 3,
        "angle_error_floor_source": ["CG1 replicas"] * 3,
        "profile_error": [np.nan, 0.2, 0.25], "profile_error_lo": [np.nan, 0.1, 0.1],
        "profile_error_hi": [np.nan, 0.3, 0.4], "profile_error_floor": [0.1] * 3,
        "profile_error_floor_source": ["CG1 replicas"] * 3,
        "fill_core_seconds": [20.0, 1.5, 1.2], "settle_core_seconds": [20.0, 1.2, 1.2],
        "production_core_seconds": [265.0, 28.0, 25.0]})


def labels(axis) -> list[str]:
    return [t.get_text() for t in axis.get_ticklabels() if t.get_text()]


def visible_labels(ax, axis) -> list[str]:
    lo, hi = ax.get_xlim() if axis is ax.xaxis else ax.get_ylim()
    return [t.get_text() for t, v in zip(axis.get_ticklabels(), axis.get_ticklocs())
            if t.get_text() and min(lo, hi) <= v <= max(lo, hi)]


def test_run_cost_bars_are_grouped_not_stacked():
    fig = Figure()
    ax = run_cost_ax(fig.subplots(), conditions())
    bars = [p for p in ax.patches]
    assert len(bars) == 9
    assert all(b.get_y() == 0 for b in bars)      # every bar starts at the axis: not stacked
    heights = sorted(round(b.get_height(), 3) for b in bars)
    assert heights[0] == 1.2 and heights[-1] == 265.0
    assert ax.get_yscale() == "log"


def test_error_plot_keeps_the_legend_off_the_data_and_labels_the_log_axis():
    fig = Figure(figsize=(6, 4))
    ax = fig.subplots()
    assert error_ax(ax, conditions(), "angle_error", "angle") is ax
    fig.canvas.draw()
    legend = ax.get_legend().get_window_extent()
    assert legend.y1 < ax.get_window_extent().y0        # below the axes
    assert len(visible_labels(ax, ax.xaxis)) >= 2        # a short span still reads
    texts = [t.get_text() for t in ax.get_legend().texts]
    assert "CG1 noise floor" in texts and "CG1 cost (reference)" in texts
    assert len(ax.containers) == 2            # the CG-n points; CG1 is the reference line
    xs = [c.lines[0].get_xdata()[0] for c in ax.containers]
    assert xs[0] != xs[1] and xs == pytest.approx([8.0, 7.0], rel=0.05)   # nudged, not moved


def test_pareto_writes_a_png(tmp_path):
    path = pareto(conditions(), tmp_path / "p.png")
    assert path.read_bytes()[:8] == b"\x89PNG\r\n\x1a\n"


def test_gsd_is_drawn_against_the_equivalent_diameter_with_the_size_limit():
    assert equivalent_diameter_mm(np.pi / 6 * 1e-9) == pytest.approx(1.0)   # 1 mm sphere
    v = np.pi / 6 * (1e-3 * np.array([1.0, 2.0, 4.0])) ** 3
    gsd = pd.DataFrame({"condition": ["cg1"] * 3 + ["cg2-weber"] * 3, "v_mid": [*v, *v],
                        "volume_fraction": [0.5, 0.3, 0.2, 0.4, 0.4, 0.2],
                        "volume_lo": [0.4, 0.2, 0.1] * 2, "volume_hi": [0.6, 0.4, 0.3] * 2,
                        "cg": [1.0] * 3 + [2.0] * 3, "rule": ["none"] * 3 + ["weber"] * 3,
                        "group": ["{}"] * 6})
    fig = Figure()
    ax = gsd_ax(fig.subplots(), gsd, size_limits={"cg2-weber": v[1]})
    assert "[mm]" in ax.get_xlabel() and "diameter" in ax.get_xlabel()
    assert np.allclose(ax.lines[0].get_xdata(), [1.0, 2.0, 4.0])
    texts = [t.get_text() for t in ax.get_legend().texts]
    assert "CG2 weber: lower size limit 2 mm" in texts
    fig.canvas.draw()
    assert len(visible_labels(ax, ax.xaxis)) >= 3
    ax2 = gsd_ax(Figure().subplots(), gsd, size_limits={"cg2-weber": float("nan")})
    assert "CG2 weber: no lower size limit located" in [t.get_text() for t in ax2.get_legend().texts]


def test_kinetics_count_time_from_production_start():
    per_case = pd.DataFrame({"case_id": ["a-r0", "a-r1", "b-r0"], "condition": ["a", "a", "b"]})
    origins = production_origins(per_case, {"a-r0": 0.3, "a-r1": 0.3, "b-r0": 0.25})
    assert origins == {"a": 0.3, "b": 0.25}
    summary = pd.DataFrame({"condition": ["a", "a"], "time": [0.4, 0.5], "granules": [3, 4],
                            "granules_lo": [2, 3], "granules_hi": [4, 5]})
    ax = kinetics_ax(Figure().subplots(), summary, "granules", "granule count", "count", origins)
    assert np.allclose(ax.lines[0].get_xdata(), [0.1, 0.2])
    assert ax.get_title() == "granule count" and "production start" in ax.get_xlabel()


def test_rotation_sense_in_the_view_along_each_axis():
    # the camera looks along +y for a y-axis drum: +omega about +y reads clockwise
    assert rotation_sense(Axis.Y, 1.0) == -1 and rotation_sense(Axis.Y, -1.0) == 1
    # for x and z the axis points at the camera: +omega reads counter-clockwise
    assert rotation_sense(Axis.X, 2.0) == 1 and rotation_sense(Axis.Z, 2.0) == 1
    assert rotation_sense(Axis.Y, 0.0) == 0


def test_speed_snapshot_states_its_shared_scale():
    fig = Figure()
    scale = SpeedScale(0.42, 3)
    ax = snapshot_ax(fig.subplots(), np.zeros((64, 64, 3), np.uint8), "t", -1, scale)
    assert ax.get_title() == "t"
    assert any("clockwise" in t.get_text() for t in ax.texts)
    bar = fig.axes[-1]
    assert "3 case(s)" in bar.get_xlabel() and "0.42" in bar.get_xlabel()


def test_importing_the_report_sets_no_backend():
    code = ("import matplotlib; matplotlib.use('svg'); import ligwf.report.write, "
            "ligwf.report.snapshots; print(matplotlib.get_backend())")
    out = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert out.stdout.strip() == "svg"


def test_sensitivity_bars_say_their_value_even_when_nothing_was_counted():
    table = pd.DataFrame({"variant": ["as set", "x0.8"], "d50": [np.nan, 0.002]})
    ax = sensitivity_ax(Figure().subplots(), table, "d50", "d50 [mm]")
    assert [t.get_text() for t in ax.texts] == ["none", "2"]
