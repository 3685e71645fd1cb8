"""The rounds of a sequential study in the report: per look, the interval of every criterion
of every condition relative to its budget (a figure: the intervals shrinking towards a
decision) and a table of the looks (level, cost so far, what the next round added, why it
stopped). Read from the study's rounds record (:mod:`ligwf.study.rounds`); nothing for a
study of one look."""

from __future__ import annotations

from pathlib import Path

from ligwf.report.sections import Figure, Section, figure_markdown
from ligwf.study import layout
from ligwf.study.rounds import Action, ExtendProduction, Look, Rounds

TITLE = "Rounds (sequential study)"
ANCHOR = "rounds"


def action_text(action: Action) -> str:
    """One action of a round in words."""
    if isinstance(action, ExtendProduction):
        return (f"{action.seconds:.3g} s more production on "
                f"{', '.join(action.case_ids)}")
    reps = action.replicas
    return (f"{len(reps)} new replica(s) of {action.condition.name} "
            f"(replica {', '.join(str(r) for r in reps)}: new seeds)")


def look_line(look: Look) -> str:
    """A look in one line: its level, cost so far, and what came of it."""
    head = (f"look {look.number} (each test at alpha {look.alpha:.3g}; "
            f"{look.core_hours:.3g} core-h run so far)")
    if look.stop:
        return f"{head}: stopped: {look.stop}"
    acts = "; ".join(action_text(a) for a in look.actions)
    return (f"{head}: next round on {look.target}: {acts} "
            f"(planned ~{look.planned_core_hours:.2g} core-h)")


def rounds_markdown(rounds: Rounds, figures: list[Figure], figures_dir: str) -> str:
    """The section's body: the method, the looks, and the criteria's half-widths per look."""
    lines = [f"A sequential study: at most {rounds.max_looks} looks, each testing at alpha "
             f"{rounds.alpha_per_look:.3g} (Bonferroni spending of {rounds.alpha:g} over the "
             "looks) with Hsu's conservative degrees of freedom (min(R1, R2) - 1), so the "
             "study's decisions stay wrong about 5 % of the time or less however many looks "
             "it takes (benchmarks/bench_coverage.py); cap "
             + (f"{rounds.max_core_hours:g} core-h." if rounds.max_core_hours else "none."), ""]
    lines += [f"- {look_line(x)}" for x in rounds.looks]
    keys = list(dict.fromkeys((c["condition"], c["label"]) for x in rounds.looks
                              for c in x.criteria if c.get("lo") is not None))
    if keys:
        lines += ["", "| condition | criterion | " + " | ".join(
            f"look {x.number}" for x in rounds.looks) + " |",
            "|---|---|" + "---|" * len(rounds.looks)]
        for cond, label in keys:
            cells = []
            for x in rounds.looks:
                c = next((c for c in x.criteria if (c["condition"], c["label"]) == (cond, label)),
                         None)
                cells.append("–" if c is None or c.get("lo") is None else
                             f"{c['state']} {c['value']:.3g} [{c['lo']:.3g}, {c['hi']:.3g}]")
            lines.append(f"| {cond} | {label} | " + " | ".join(cells) + " |")
    if figures:
        lines += ["", figure_markdown(figures, figures_dir)]
    return "\n".join(lines)


def draw_rounds(rounds: Rounds, path: Path) -> Path:
    """Each criterion's interval over its budget per look, one line per condition and
    criterion (the band +-1 is the budget: inside it passes, wholly outside it fails)."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, ax = plt.subplots(figsize=(7, 4))
    keys = list(dict.fromkeys((c["condition"], c["label"]) for x in rounds.looks
                              for c in x.criteria if c.get("lo") is not None and c.get("budget")))
    for k, (cond, label) in enumerate(keys):
        pts = [(x.number, c) for x in rounds.looks for c in x.criteria
               if (c["condition"], c["label"]) == (cond, label) and c.get("lo") is not None
               and c.get("budget")]
        shift = (k - (len(keys) - 1) / 2) * 0.04
        n = [p[0] + shift for p in pts]
        lo = [p[1]["lo"] / p[1]["budget"] for p in pts]
        hi = [p[1]["hi"] / p[1]["budget"] for p in pts]
        mid = [p[1]["value"] / p[1]["budget"] for p in pts]
        bars = ax.errorbar(n, mid, yerr=[[m - a for m, a in zip(mid, lo)],
                                         [b - m for m, b in zip(mid, hi)]],
                           marker="o", capsize=3, label=f"{cond}: {label}")
        bars[0].set_linestyle("-")
    ax.axhspan(-1, 1, color="0.9", zorder=0)
    ax.axhline(1, color="0.5", lw=0.8)
    ax.axhline(-1, color="0.5", lw=0.8)
    ax.set_xlabel("look")
    ax.set_ylabel("value / budget (interval)")
    ax.set_xticks([x.number for x in rounds.looks])
    ax.set_title("Intervals per look (grey: inside the budget)")
    if keys:
        ax.legend(fontsize=6, loc="best")
    fig.tight_layout()
    path.parent.mkdir(parents=True, exist_ok=True)
    fig.savefig(path, dpi=110)
    plt.close(fig)
    return path


def rounds_sections(rounds: Rounds, figures_dir: Path) -> list[Section]:
    """The report's rounds section (none for a study without looks)."""
    if not rounds.looks:
        return []
    fig = Figure("Intervals per look", draw_rounds(rounds, figures_dir / layout.FIGURE_ROUNDS))
    return [Section(TITLE, ANCHOR, rounds_markdown(rounds, [fig], figures_dir.name))]
