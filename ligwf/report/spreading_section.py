"""Placed liquid's spreading in a study's report: ``spreading.csv`` (one row per CG-n
level against its group's CG1) and the section that shows it, for any study whose cases
placed liquid in a dry bed (``liquid.placement: granules``); nothing otherwise.

The engine moves liquid only at bridge ruptures, so liquid spreads by a walk over contacts
whose step is one particle: about n^2 times faster in physical space at CG-n, which no CG
rule corrects. The section says how much faster it was measured
(:mod:`ligwf.inference.spreading`, its tables made by
:func:`ligwf.inference.decide.decide_study`), beside the CG1 seeds' own spread (the null).
"""

from __future__ import annotations

import math

import pandas as pd

from ligwf.inference.spreading import LEVEL, spreading_time_meaning
from ligwf.report.sections import Section


def _num(v, fmt: str = ".3g") -> str:
    try:
        v = float(v)
    except (TypeError, ValueError):
        return "–"
    return format(v, fmt) if math.isfinite(v) else "–"


def spreading_section(cases: pd.DataFrame, levels: pd.DataFrame) -> list[Section]:
    """The report section (none when no case placed liquid)."""
    if cases.empty:
        return []
    lines = [f"Placed liquid spreads only when a bridge ruptures (the engine splits its "
             f"liquid between the two particles), a walk over contacts whose step is one "
             f"particle: about n^2 times faster in physical space at CG-n, which no CG rule "
             f"corrects. Spreading time: {spreading_time_meaning()}.", "",
             "| case | CG | dry at start | spreading time [rev] | dry share of liquid at "
             "the end | dry particles wet at the end |", "|---|---|---|---|---|---|"]
    for _, r in cases.sort_values(["group", "cg", "rule", "replica"]).iterrows():
        t = _num(r.t_spread_rev) + (" (not reached)" if r.censored else "")
        lines.append(f"| {r.case_id} | {r.cg:g} | {int(r.dry_particles)} of "
                     f"{int(r.particles)} | {t} | {_num(r.dry_content_share_end)} | "
                     f"{_num(r.dry_wet_share_end)} |")
    if not levels.empty:
        lines += ["", f"CG-n against CG1: the rate ratio is the CG1 spreading time over the "
                  f"level's (geometric means), its {LEVEL:.0%} interval Welch's t on the log "
                  "times (its coverage on so few runs is not measured by a benchmark); the "
                  "exponent k = log ratio / log n, against the n^2 expected.", "",
                  "| group | rule | CG | runs (CG1) | rate ratio [95 %] | exponent k [95 %] | "
                  "n^2 | n^2 inside | faster | CG1 seeds' largest ratio |",
                  "|---|---|---|---|---|---|---|---|---|---|"]
        for _, r in levels.iterrows():
            bound = " (a bound: a run never reached the level)" if r.is_bound else ""
            lines.append(
                f"| {r.group} | {r.rule} | {r.cg:g} | {int(r.runs)} ({int(r.cg1_runs)}) | "
                f"{_num(r.rate_ratio)} [{_num(r.rate_ratio_low)}, {_num(r.rate_ratio_high)}]"
                f"{bound} | {_num(r.exponent, '.2g')} [{_num(r.exponent_low, '.2g')}, "
                f"{_num(r.exponent_high, '.2g')}] | {r.expected_ratio:g} | "
                f"{'yes' if r.contains_expected else 'no'} | "
                f"{'yes' if r.above_one else 'not shown'} | {_num(r.cg1_spread)} |")
    return [Section("Liquid spreading", "liquid-spreading", "\n".join(lines))]
