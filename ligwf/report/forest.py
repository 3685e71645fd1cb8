"""The verdict as one picture: per CG level each criterion's interval against its budget (a
forest plot) with the speedup beside, first on the report page and in its figures folder.

Read only from the verdict record (:class:`ligwf.inference.verdict.Verdict`), so the picture
shows what the verdict table says and nothing else: one panel per criterion (its own x axis
in the verdict's unit: degrees for the angle, the share or relative difference for the
others), one row per level in every panel (so a row across the panels is one level), the
budget shaded (+-budget for a signed difference, [0, budget] for an error that must stay
below it), the interval as a bar and the estimate as a dot coloured by the criterion's
state; a criterion without an interval says why at its row ("not assessed": e.g. the norm
criteria of a level judged against an extrapolated CG1). The last panel is the speedup
with its interval (log scale).

Every interval, estimate and speedup is drawn as a line whose ``gid`` is
``"<condition>|<criterion>"`` (:func:`gid`), so a test can read the figure's data back.
"""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pandas as pd
from matplotlib.figure import Figure

from ligwf.inference.equivalence import FAIL, PASS, UNDECIDED
from ligwf.inference.budget import criteria, signed_names
from ligwf.inference.registry import RELATIVE, SIGNED
from ligwf.report.figures import log_scale, save
from ligwf.inference.verdict import Verdict

#: criteria judged on a signed difference: their budget is +-tolerance
#: the speedup's panel and gid suffix
SPEEDUP = "speedup"
#: colours of the states (the terminal's words for them: :mod:`ligwf.report.verdict_text`)
COLOURS = {PASS: "tab:green", FAIL: "tab:red", UNDECIDED: "tab:orange"}
#: the x-axis words of a criterion kind: what its value is
_WHAT = {SIGNED: "CG-n - CG1", RELATIVE: "(CG-n - CG1) / CG1"}


def gid(condition: str, criterion: str) -> str:
    """The ``gid`` of a drawn row: ``"<condition>|<criterion>"``."""
    return f"{condition}|{criterion}"


def forest_rows(verdict: Verdict) -> pd.DataFrame:
    """One row per (sweep group, level, criterion) of the verdict, in the verdict's order:
    what the picture draws (value, lo, hi and budget in the criterion's unit; ``signed``:
    its budget is +-budget) and the level's speedup with its interval."""
    rows = []
    for g in verdict.groups:
        for c in g.conditions:
            for r in c.criteria:
                rows.append({"group": g.group, "condition": c.name, "level_state": c.state,
                             "too_short": bool(c.too_short),
                             "speedup": c.speedup, "speedup_lo": c.speedup_lo,
                             "speedup_hi": c.speedup_hi, "criterion": r.name,
                             "label": r.label, "unit": r.unit, "state": r.state,
                             "assessed": r.assessed, "value": r.value, "lo": r.lo, "hi": r.hi,
                             "budget": r.budget, "signed": r.name in signed_names()})
    return pd.DataFrame(rows)


def _axis_label(name: str, label: str, unit: str) -> str:
    kind = next((s.estimate for s in criteria() if s.name == name), "")
    what = _WHAT.get(kind, "error")
    return f"{label}\n{what}" + (f" [{unit}]" if unit else "")


def _criterion_panel(ax, rows: pd.DataFrame, ys: dict[str, float]) -> None:
    """One criterion's rows: the budget band, each level's interval and estimate, or the
    reason it has none."""
    first = rows.iloc[0]
    budgets = rows["budget"].to_numpy(float)
    budget = float(np.nanmax(budgets)) if np.isfinite(budgets).any() else math.nan
    if math.isfinite(budget):
        left = -budget if first["signed"] else 0.0
        ax.axvspan(left, budget, color="tab:green", alpha=0.12, lw=0)
        for x in ((-budget, budget) if first["signed"] else (budget,)):
            ax.axvline(x, color="tab:green", lw=0.8, ls="--")
    ax.axvline(0.0, color="k", lw=0.5)
    for _, r in rows.iterrows():
        y, colour = ys[r["condition"]], COLOURS.get(r["state"], "grey")
        tag = gid(r["condition"], r["criterion"])
        if math.isfinite(r["lo"]) and math.isfinite(r["hi"]):
            ax.plot([r["lo"], r["hi"]], [y, y], color=colour, lw=2.2, solid_capstyle="butt",
                    gid=tag)
        if math.isfinite(r["value"]):
            ax.plot([r["value"]], [y], "o", color=colour, ms=5, gid=tag + "|value")
        if not (math.isfinite(r["lo"]) and math.isfinite(r["hi"])):
            words = r["state"] if not r["assessed"] else f"{r['state']}, no interval"
            ax.text(0.5, y, words, transform=ax.get_yaxis_transform(), ha="center",
                    va="center", fontsize=7, color="grey")
    ax.set_xlabel(_axis_label(first["criterion"], first["label"], first["unit"]), fontsize=8)
    ax.tick_params(axis="x", labelsize=7)
    ax.grid(alpha=0.3, axis="x")


def _speedup_panel(ax, levels: pd.DataFrame, ys: dict[str, float]) -> None:
    for _, r in levels.iterrows():
        y, tag = ys[r["condition"]], gid(r["condition"], SPEEDUP)
        if math.isfinite(r["speedup_lo"]) and math.isfinite(r["speedup_hi"]):
            ax.plot([r["speedup_lo"], r["speedup_hi"]], [y, y], color="tab:blue", lw=2.2,
                    gid=tag)
        if math.isfinite(r["speedup"]):
            ax.plot([r["speedup"]], [y], "s", color="tab:blue", ms=5, gid=tag + "|value")
    values = levels[["speedup", "speedup_lo", "speedup_hi"]].to_numpy(float).ravel()
    log_scale(ax, "x", values, "no speedup")
    ax.set_xlabel("speedup\n(CG1 core-s / level's)", fontsize=8)
    ax.tick_params(axis="x", labelsize=7)
    ax.grid(alpha=0.3, axis="x")


def forest_figure(verdict: Verdict) -> Figure | None:
    """The forest plot of ``verdict`` (None when it judged no level)."""
    rows = forest_rows(verdict)
    if rows.empty:
        return None
    levels = rows.drop_duplicates("condition")
    order = list(levels["condition"])
    ys = {name: float(len(order) - 1 - k) for k, name in enumerate(order)}
    criteria = list(dict.fromkeys(rows["criterion"]))
    fig = Figure(figsize=(2.3 * (len(criteria) + 1) + 1.5, 0.45 * len(order) + 1.6))
    axes = fig.subplots(1, len(criteria) + 1, sharey=True, squeeze=False)[0]
    for ax, name in zip(axes, criteria):
        _criterion_panel(ax, rows[rows["criterion"] == name], ys)
    _speedup_panel(axes[-1], levels, ys)
    axes[0].set_yticks([ys[n] for n in order],
                       [f"{n}\n({s}{'; runs too short' if short else ''})"
                        for n, s, short in zip(order, levels["level_state"],
                                               levels["too_short"])],
                       fontsize=8)
    axes[0].set_ylim(-0.7, len(order) - 0.3)
    shown = verdict.statistics.get("interval_level")
    fig.suptitle("Verdict: each criterion's interval"
                 + (f" ({100 * float(shown):.3g} %)" if shown else "")
                 + " against its budget (shaded); green pass, red fail, orange undecided",
                 fontsize=9)
    fig.subplots_adjust(wspace=0.12)
    return fig


def forest(verdict: Verdict, path: Path) -> Path | None:
    """Write the forest plot of ``verdict`` as PNG to ``path`` (None: nothing to draw)."""
    fig = forest_figure(verdict)
    return save(fig, path) if fig is not None else None
