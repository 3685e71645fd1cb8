"""The verdict as one picture (issue 45 item 5): the forest plot's rows are the verdict
record's criteria with their intervals (read back from the drawn lines, not a screenshot),
in the verdict's units; the terminal's compact table fits 100 columns; the error-vs-run-time
figure shows the verdict's numbers; a sweep without CG1 (extrapolated CG1) draws too; the
report page shows the picture first."""

from __future__ import annotations

import math

import numpy as np
import pytest
from rich.console import Console

from ligwf.inference.equivalence import FAIL, PASS, UNDECIDED
from ligwf.inference.registry import NOT_ASSESSED, CriterionResult
from ligwf.report.figures import pareto_figure
from ligwf.report.forest import SPEEDUP, forest, forest_figure, forest_rows, gid
from ligwf.report.forest_text import WIDTH, bar, compact_lines
from ligwf.inference.verdict import ConditionVerdict, GroupVerdict, Verdict, decide
from ligwf.report.html import render_page
from ligwf.report.sections import Figure, Section, ordered
from ligwf.report.verdict_text import verdict_renderables, verdict_section
from ligwf.report.write import verdict_sections
from ligwf.study import layout
from ligwf.scene.accept import AcceptSettings
from tests.inference.test_verdict import CG1, GROUP, PASSING, runs, study, verdict


def drawn(fig) -> dict[str, np.ndarray]:
    """gid -> x data of every line of the figure that carries a gid."""
    return {line.get_gid(): np.asarray(line.get_xdata(), float)
            for ax in fig.axes for line in ax.lines if line.get_gid()}


def test_forest_rows_are_the_verdicts_criteria_with_their_intervals_in_degrees():
    v = verdict(CG1, runs(2, "weber", [42.0, 42.2, 41.9]), runs(3, "weber", [40.0, 40.2, 39.9]))
    fig = forest_figure(v)
    lines = drawn(fig)
    seen = 0
    for c in v.groups[0].conditions:
        for r in c.criteria:
            tag = gid(c.name, r.name)
            if math.isfinite(r.lo):
                assert lines[tag] == pytest.approx([r.lo, r.hi])     # the record's interval
                assert lines[tag + "|value"] == pytest.approx([r.value])
                seen += 1
            else:
                assert tag not in lines
        assert lines[gid(c.name, SPEEDUP)] == pytest.approx([c.speedup_lo, c.speedup_hi])
    assert seen >= 6
    angle = v.groups[0].conditions[0].criteria[0]
    assert angle.name == "angle_deg" and angle.state == FAIL
    # degrees, not percent: the drawn interval is the difference of the run means in deg
    assert lines[gid("cg2-weber", "angle_deg")] == pytest.approx([angle.lo, angle.hi])
    assert 1.5 < angle.value < 2.5
    labels = [a.get_xlabel() for a in fig.axes]
    assert labels[0].startswith("angle of repose") and "[deg]" in labels[0]
    assert "%" not in labels[0]
    assert [t.get_text().split("\n")[0] for t in fig.axes[0].get_yticklabels()] == \
        ["cg2-weber", "cg3-weber"]
    # the budget band: +-1 deg shaded on the angle's panel
    (band,) = fig.axes[0].patches
    assert (band.get_x(), band.get_x() + band.get_width()) == pytest.approx((-1.0, 1.0))


def test_a_sweep_without_cg1_draws_its_norm_criteria_as_not_assessed(tmp_path):
    arms = [runs(n, "weber", [40.0 + 0.3 * n + 0.1 * k for k in range(3)]) for n in (2, 3, 4)]
    conditions, cases, profiles = study(*arms)
    v = decide(conditions, AcceptSettings(), {GROUP: PASSING}, cases, profiles,
               size_ratio=0.01)
    levels = v.groups[0].conditions
    assert levels and all(
        {r.name: r.state for r in c.criteria}["profile_error"] == NOT_ASSESSED for c in levels)
    fig = forest_figure(v)
    texts = [t.get_text() for ax in fig.axes for t in ax.texts]
    assert texts.count(NOT_ASSESSED) >= len(levels)
    lines = drawn(fig)
    for c in levels:
        assert gid(c.name, "profile_error") not in lines
        angle = {r.name: r for r in c.criteria}["angle_deg"]
        if math.isfinite(angle.lo):
            assert lines[gid(c.name, "angle_deg")] == pytest.approx([angle.lo, angle.hi])
    assert forest(v, tmp_path / "f.png").read_bytes()[:4] == b"\x89PNG"
    table = [line for line, _ in compact_lines(v)]
    assert any(NOT_ASSESSED in line for line in table)


def _long_verdict() -> Verdict:
    """Four levels of six criteria with the widest numbers a cell can hold."""
    names = [("angle_deg", "angle of repose", "deg"), ("profile_error", "velocity profile", ""),
             ("rigid_share", "rigid-block frames", ""), ("flowing_layer", "flowing layer", ""),
             ("gsd_error", "GSD", ""), ("field_error", "continuum fields", "")]
    states = [PASS, FAIL, UNDECIDED, NOT_ASSESSED]
    levels = []
    for k, cg in enumerate((2, 3, 4, 6)):
        crit = tuple(CriterionResult(name, label, unit, states[(k + j) % 4],
                                     value=-1.23456e-5 * (j + 1), lo=-123456.7, hi=0.000123456,
                                     budget=0.0123456) if states[(k + j) % 4] != NOT_ASSESSED
                     else CriterionResult(name, label, unit, NOT_ASSESSED, budget=0.05,
                                          note="not assessed: no control")
                     for j, (name, label, unit) in enumerate(names))
        levels.append(ConditionVerdict('{"process.rotation.rpm": 20}', float(cg), "weber", 24,
                                       123.456, -1.2345e-5, 98765.4321, crit))
    return Verdict((GroupVerdict('{"process.rotation.rpm": 20}', tuple(levels), "none meets"),),
                   {"angle_deg": 1.0}, {})


def test_the_terminal_table_fits_100_columns_for_four_levels_and_six_criteria():
    v = _long_verdict()
    lines = compact_lines(v)
    assert len(lines) == 4 * (1 + 6)
    assert max(len(line) for line, _ in lines) <= WIDTH
    # printed on a wide terminal, the verdict's table lines are still at most 100 wide
    console = Console(width=250, record=True, color_system=None)
    for item in verdict_renderables(v):
        console.print(item, highlight=False)
    printed = console.export_text().splitlines()
    table = [p for p in printed if any(p.rstrip() == line for line, _ in lines)]
    assert len(table) == len(lines)
    assert max(len(p.rstrip()) for p in table) <= WIDTH
    # every criterion of every level is a line of its own, with its state
    for c in v.groups[0].conditions:
        for r in c.criteria:
            assert any(line.startswith(f"  {r.label}") and r.state in line
                       for line, _ in lines)


def test_the_bar_draws_the_interval_against_the_budget():
    b = bar(0.0, -0.5, 0.5, 1.0, True, width=21)
    assert b.count("|") == 2 and b[10] == "o" and "=" in b
    assert b.index("|") < b.index("=") and b.rindex("|") > b.rindex("=")
    outside = bar(2.0, 1.5, 2.5, 1.0, True, width=21)
    assert outside.rindex("|") < outside.index("=")      # wholly beyond the budget


def test_the_error_vs_run_time_figure_shows_the_verdicts_numbers():
    conditions, cases, profiles = study(CG1, runs(2, "weber", [42.0, 42.2, 41.9]),
                                        runs(3, "weber", [40.0, 40.2, 39.9]))
    v = decide(conditions, AcceptSettings(), {GROUP: PASSING}, cases, profiles)
    conditions = conditions.assign(production_core_rate_k=[8.0, 1.0, 0.5],
                                   angle_error=[np.nan, 0.05, 0.001],
                                   profile_error=[np.nan, 0.1, 0.05])
    fig = pareto_figure(conditions, forest_rows(v))
    lines = {ln.get_gid(): np.asarray(ln.get_ydata(), float)
             for ln in fig.axes[0].lines if ln.get_gid()}
    for c in v.groups[0].conditions:
        angle = {r.name: r for r in c.criteria}["angle_deg"]
        assert lines[gid(c.name, "angle_deg")] == pytest.approx([angle.lo, angle.hi])
        assert lines[gid(c.name, "angle_deg") + "|value"] == pytest.approx([angle.value])
    assert "[deg]" in fig.axes[0].get_ylabel()
    # without a verdict the panel keeps the conditions table's relative error (in %)
    plain = pareto_figure(conditions)
    assert plain.axes[0].get_ylabel() == "error [%]"


def test_the_picture_is_first_in_the_verdict_section():
    v = verdict(CG1, runs(2, "weber", [40.1, 39.9, 40.0]))
    md = verdict_section(v, "figures/verdict_forest.png")
    body = md.splitlines()
    assert body[0] == "## Verdict" and body[2].startswith("![Verdict")
    assert "(figures/verdict_forest.png)" in body[2]
    assert not any(line.startswith("![") for line in verdict_section(v).splitlines())


def test_the_report_page_opens_with_the_forest_plot_from_its_figures_folder(tmp_path):
    v = verdict(CG1, runs(2, "weber", [40.1, 39.9, 40.0]))
    path = forest(v, tmp_path / layout.FIGURES_DIR / layout.FIGURE_VERDICT_FOREST)
    other = Section("Cases", "cases", "a table")
    sections = ordered([other, *verdict_sections(v, Figure("Verdict", path))])
    assert sections[0].anchor == "verdict"
    assert sections[0].markdown.splitlines()[0] == (
        "![Verdict: each criterion's interval against its budget, the speedup beside]"
        f"({layout.FIGURES_DIR}/{layout.FIGURE_VERDICT_FOREST})")
    assert (tmp_path / layout.FIGURES_DIR / layout.FIGURE_VERDICT_FOREST).is_file()
    page = render_page("t", "", sections)
    assert page.index(layout.FIGURE_VERDICT_FOREST) < page.index("a table")
