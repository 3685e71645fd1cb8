"""The verdict (:mod:`ligwf.inference.verdict`) as the report's first section (markdown:
summary.md shows it, index.html renders it, :mod:`ligwf.report.sections`) and as the
terminal lines ``ligwf study`` and ``ligwf report`` end with (rich).

All three show the same facts: per sweep group its sentence (the cheapest level that meets
the budget, or that none does and why), then per CG level and rule the speedup with its
interval and each criterion's state with its value, interval and budget; undecided
criteria say what would decide them, unassessed ones why. Every sentence about the statistics
(interval level, alpha, degrees of freedom, family) is written from the verdict's record
(:mod:`ligwf.inference.verdict_statistics`).
"""

from __future__ import annotations

import math

from rich.text import Text

from ligwf.inference.equivalence import FAIL, PASS, UNDECIDED
from ligwf.inference.budget import criteria, signed_names
from ligwf.inference.registry import CriterionResult
from ligwf.report.forest_text import compact_lines
from ligwf.inference.verdict import FAILS, MEETS, ConditionVerdict, GroupVerdict, Verdict, band_text
from ligwf.inference.verdict_statistics import (cheapest_disclosure, method_text,
                                             shown_within_heading)

TITLE = "Verdict"


def _within(name: str) -> str:
    """How a criterion's budget reads: ``+-`` for a signed difference, else ``<= ``."""
    return "+-" if name in signed_names() else "<= "


#: rich styles of the states
STYLE = {PASS: "green", FAIL: "red", UNDECIDED: "yellow", MEETS: "bold green",
         FAILS: "bold red"}


def _num(v: float) -> str:
    return "–" if not math.isfinite(v) else f"{v:.3g}"


def group_title(group: str) -> str:
    """A sweep group for a reader: ``all cases`` for the study without swept values."""
    return "all cases" if group in ("{}", "") else group


def budget_line(accept: dict) -> str:
    """The tolerances the verdict was decided with, in the block's order."""
    parts = []
    for s in criteria():
        if s.name not in accept:
            continue
        tol = accept[s.name]
        if tol is None:
            parts.append(f"{s.label}: not in the budget")
            continue
        unit = f" {s.unit}" if s.unit else ""
        parts.append(f"{s.label} {_within(s.name)}{tol:g}{unit}")
    return "; ".join(parts)


def cell(r: CriterionResult) -> str:
    """A criterion as one table cell: its state and value [interval] (the budget is in
    the column's header)."""
    if not r.assessed:
        return r.state
    return f"{r.state} {band_text(r.value, r.lo, r.hi)}"


def shown_within(c: ConditionVerdict) -> str:
    """The errors a level is shown to stay within: each assessed criterion's largest
    |error| its interval allows, in its unit (``angle of repose 2.9 deg, ...``)."""
    parts = [f"{r.label} {_num(r.bound)}{' ' + r.unit if r.unit else ''}"
             for r in c.criteria if r.assessed and math.isfinite(r.bound)]
    return ", ".join(parts) if parts else "nothing (no interval)"


def _notes(g: GroupVerdict) -> list[str]:
    """Levels whose runs are too short to show a steady state (first: it qualifies every
    interval of the level); what would decide each undecided criterion; why a criterion
    was not assessed or measured, once per group when it is the same for every condition."""
    out: list[str] = [f"{c.name}: {c.too_short}" for c in g.conditions if c.too_short]
    for c in g.conditions:
        out += [f"{c.name}, {r.label}: {r.note}" for r in c.criteria if r.assessed and r.note]
    seen: list[str] = []
    for c in g.conditions:
        seen += [f"{r.label}: {r.note}" for r in c.criteria if not r.assessed and r.note]
    return out + list(dict.fromkeys(seen))


def _columns(g: GroupVerdict) -> list[str]:
    """The criteria's headers with their budget (one per group: the floor is the group's)."""
    if not g.conditions:
        return []
    heads = []
    for k, r in enumerate(g.conditions[0].criteria):
        budgets = [c.criteria[k].budget for c in g.conditions
                   if math.isfinite(c.criteria[k].budget)]
        unit = f" {r.unit}" if r.unit else ""
        heads.append(f"{r.label} ({_within(r.name)}{_num(max(budgets))}{unit})" if budgets
                     else r.label)
    return heads


def sentence(g: GroupVerdict, stats: dict) -> str:
    """The group's sentence, with what naming the cheapest of its levels costs."""
    note = cheapest_disclosure(stats, len(g.conditions)) if g.cheapest else ""
    return f"{g.sentence} {note}" if note else g.sentence


def group_markdown(g: GroupVerdict, several: bool, stats: dict | None = None) -> list[str]:
    lines = ([f"### {group_title(g.group)}", ""] if several else [])
    lines += [f"**{sentence(g, stats or {})}**", ""]
    if not g.conditions:
        return lines
    cols = _columns(g)
    lines += ["| condition | replicas | speedup (core-s) | verdict | " + " | ".join(cols) + " |",
              "|---|---|---|---|" + "---|" * len(cols)]
    for c in g.conditions:
        lines.append(f"| {c.name} | {c.replicas} | "
                     f"{band_text(c.speedup, c.speedup_lo, c.speedup_hi)} | {c.state} | "
                     + " | ".join(cell(r) for r in c.criteria) + " |")
    lines += ["", shown_within_heading(stats or {}), ""]
    lines += [f"- **{c.name}** (speedup {_num(c.speedup)}): {shown_within(c)}"
              for c in g.conditions]
    notes = _notes(g)
    if notes:
        lines += [""] + [f"- {n}" for n in notes]
    return lines + [""]


def verdict_section(verdict: Verdict, figure: str | None = None) -> str:
    """The verdict as the report's first markdown section; ``figure`` (a path relative to
    the report folder): its forest plot (:mod:`ligwf.report.forest`), shown first."""
    lines = [f"## {TITLE}", ""]
    if figure:
        lines += [f"![Verdict: each criterion's interval against its budget, the speedup "
                  f"beside]({figure})", ""]
    lines += [
             f"Budget (`accept:` block): {budget_line(verdict.accept)}. The unit is the run "
             f"(its steady-window mean). {method_text(verdict.statistics)} Coverage and error "
             "rates measured by `benchmarks/bench_coverage.py`. Control twins are not "
             "candidates.", ""]
    if not verdict.groups:
        return "\n".join(lines + ["No sweep group with a CG1 reference and a CG level to "
                                  "judge.", ""])
    several = len(verdict.groups) > 1
    for g in verdict.groups:
        lines += group_markdown(g, several, verdict.statistics)
    return "\n".join(lines)


def verdict_renderables(verdict: Verdict) -> list:
    """Rich renderables for the terminal: per group its sentence, then the forest plot as
    a compact table (:mod:`ligwf.report.forest_text`: a line per level and per criterion,
    each at most 100 characters), what each level is shown to stay within and the notes."""
    out: list = [Text(f"{TITLE} ({budget_line(verdict.accept)})", style="bold")]
    for g in verdict.groups:
        title = group_title(g.group)
        said = sentence(g, verdict.statistics)
        out.append(Text(f"{title}: {said}" if len(verdict.groups) > 1 else said,
                        style="bold green" if g.cheapest else "bold"))
        if not g.conditions:
            continue
        out += [Text(line, style=STYLE.get(state, "dim"), no_wrap=True, overflow="crop")
                for line, state in compact_lines(verdict, g.group)]
        out += [Text(f"  {c.name} is shown to stay within: {shown_within(c)}")
                for c in g.conditions]
        out += [Text(f"  {n}", style="dim") for n in _notes(g)]
    return out
