"""The forest plot (:mod:`ligwf.report.forest`) as the terminal prints it: per level a head
line (its state and speedup), then one line per criterion with its state, estimate
[interval], budget and a bar drawing the interval against the budget, every line at most
:data:`WIDTH` characters whatever the numbers (``ligwf report`` and ``ligwf study`` end with
it, :func:`ligwf.report.verdict_text.verdict_renderables`).

The bar, :data:`BAR` characters: ``|`` the budget's edges (+-budget for a signed difference,
0 and the budget for an error), ``=`` the interval, ``o`` the estimate, ``-`` the rest of
the criterion's own scale (the largest of the budget and the interval's ends, so both fit).
"""

from __future__ import annotations

import math

from ligwf.report.forest import forest_rows
from ligwf.inference.verdict import Verdict

#: the widest line the table prints (a terminal of 100 columns shows it unwrapped)
WIDTH = 100
#: characters of the interval bar
BAR = 21
#: widths of the criterion's columns: label, state, estimate [interval], budget
LABEL, STATE, ESTIMATE, BUDGET = 18, 12, 29, 12
INDENT = "  "


def short(v: float) -> str:
    """A number in at most 8 characters (``-1.2e-05``); ``–`` for none."""
    if not math.isfinite(v):
        return "–"
    text = f"{v:.3g}"
    return text if len(text) <= 8 else f"{v:.1e}"


def estimate_text(value: float, lo: float, hi: float) -> str:
    """``-0.31 [-0.82, 0.2]``, or the value alone without an interval."""
    if math.isfinite(lo) and math.isfinite(hi):
        return f"{short(value)} [{short(lo)}, {short(hi)}]"
    return short(value)


def budget_text(budget: float, signed: bool, unit: str) -> str:
    """``+-1 deg`` or ``<= 0.1``."""
    if not math.isfinite(budget):
        return ""
    return f"{'+-' if signed else '<= '}{short(budget)}" + (f" {unit}" if unit else "")


def bar(value: float, lo: float, hi: float, budget: float, signed: bool,
        width: int = BAR) -> str:
    """The interval against the budget in ``width`` characters (blank without a budget)."""
    if not math.isfinite(budget) or budget <= 0:
        return ""
    ends = [x for x in (value, lo, hi) if math.isfinite(x)]
    top = max([budget, *(abs(x) for x in ends)]) * 1.05
    left = -top if signed else min([0.0, *ends]) * 1.05
    scale = (width - 1) / (top - left)

    def at(x: float) -> int:
        return min(width - 1, max(0, round((x - left) * scale)))

    cells = ["-"] * width
    if math.isfinite(lo) and math.isfinite(hi):
        for k in range(at(lo), at(hi) + 1):
            cells[k] = "="
    for edge in ((-budget, budget) if signed else (0.0, budget)):
        cells[at(edge)] = "|"
    if math.isfinite(value):
        cells[at(value)] = "o"
    return "".join(cells)


def _fit(text: str, width: int) -> str:
    return text if len(text) <= width else text[: width - 1] + "…"


def head_line(condition: str, state: str, speedup: float, lo: float, hi: float) -> str:
    """A level's line: its name, its state and its speedup [interval] (the name shortened
    when the line would be wider than :data:`WIDTH`)."""
    tail = f"  {state}  speedup {estimate_text(speedup, lo, hi)}"
    return _fit(condition, WIDTH - len(tail)) + tail


def criterion_line(label: str, state: str, value: float, lo: float, hi: float,
                   budget: float, signed: bool, unit: str) -> str:
    """A criterion's line under its level (at most :data:`WIDTH` characters)."""
    assessed = math.isfinite(value)
    return (f"{INDENT}{_fit(label, LABEL):<{LABEL}} {_fit(state, STATE):<{STATE}} "
            f"{_fit(estimate_text(value, lo, hi) if assessed else '', ESTIMATE):<{ESTIMATE}} "
            f"{_fit(budget_text(budget, signed, unit), BUDGET):<{BUDGET}} "
            f"{bar(value, lo, hi, budget, signed) if assessed else ''}").rstrip()


def compact_lines(verdict: Verdict, group: str | None = None) -> list[tuple[str, str]]:
    """(line, state) of the verdict's levels (of one sweep ``group``, or all): what the
    terminal prints, each line at most :data:`WIDTH` characters; ``state`` is the level's
    on a head line, the criterion's otherwise (the caller colours by it)."""
    rows = forest_rows(verdict)
    if rows.empty:
        return []
    if group is not None:
        rows = rows[rows["group"] == group]
    out = []
    for condition, sub in rows.groupby("condition", sort=False):
        first = sub.iloc[0]
        state = first["level_state"] + ("; runs too short" if first["too_short"] else "")
        out.append((head_line(str(condition), state, first["speedup"],
                              first["speedup_lo"], first["speedup_hi"]),
                    first["level_state"]))
        for _, r in sub.iterrows():
            out.append((criterion_line(r["label"], r["state"], r["value"], r["lo"], r["hi"],
                                       r["budget"], bool(r["signed"]), r["unit"]), r["state"]))
    return out
