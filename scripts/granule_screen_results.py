"""docs/results/granule_screen/: phase 1 of the registered granule screen (issue 47 item 3,
criterion.md committed before the runs): one seed of each condition scored on the four
registered points, the best picked by the registered rule.

Writes ``growth_rows.csv`` (every start frame of every run: held granules, survival,
co-movement, the wall test; ligwf.analysis.granules.growth), ``conditions.csv`` (one row per
condition: its measures, points and rank) and ``README.md`` from them; ``--check`` rebuilds
the README from the committed tables and fails when it differs.

    bash scripts/granule_screen.sh runs            # runs/granule_screen/S1..S4
    .venv/bin/python scripts/granule_screen_results.py runs/granule_screen
"""

from __future__ import annotations

import json
import math
import sys
from pathlib import Path

import numpy as np
import pandas as pd

sys.path.insert(0, str(Path(__file__).resolve().parent))
from results_readme import ROOT, csv_text, number, parser, write_or_check  # noqa: E402

from ligwf.analysis.granules.growth import GrowthSettings, hac_slope  # noqa: E402
from ligwf.analysis.granules.growth_study import Criteria, measure_case  # noqa: E402

OUT = ROOT / "docs" / "results" / "granule_screen"
#: the registered settings (criterion.md): W = 1.3 s, start frames every 0.1 s from W
SETTINGS = GrowthSettings(hold_time=1.3, cadence=0.05, stride=0.1, start_after=1.3)
CONDITIONS = {"S1": ("washino", "placed nuclei"), "S2": ("washino", "uniform"),
              "S3": ("easo", "placed nuclei"), "S4": ("easo", "uniform")}
LAST_REVOLUTIONS = 10.0
POINTS = (("exists", "share_10 >= 0.02"), ("survives", "mean survival >= 0.5"),
          ("grows", "share_10 slope's 95 % interval above 0"),
          ("comoves", "mean co-movement ratio <= 0.5"))


def case_folder(study: Path, name: str) -> Path | None:
    """The one case folder of condition ``name`` (its seed r0), or None when not run."""
    found = sorted(p.parent for p in (study / name).glob("cg1-*/manifest.json"))
    return found[0] if found else None


def status_of(case: Path) -> tuple[str, float]:
    m = json.loads((case / "manifest.json").read_text())
    return str(m.get("status")), float(m.get("core_seconds") or math.nan)


def condition_row(name: str, rows: pd.DataFrame, flows: pd.DataFrame, status: str,
                  core_s: float, criteria: Criteria = Criteria()) -> dict:
    model, liquid = CONDITIONS[name]
    out = {"condition": name, "model": model, "liquid": liquid, "status": status,
           "core_minutes": core_s / 60.0, "start_frames": len(rows)}
    if rows.empty:
        return {**out, **{p: False for p, _ in POINTS}, "wet_mass": False, "points": 0}
    lag = int(round(SETTINGS.hold_time / SETTINGS.stride)) + 1
    slope = hac_slope(rows["time"].to_numpy(), rows["share_10"].to_numpy(), lag)
    last = rows[rows.revolutions >= rows.revolutions.max() - LAST_REVOLUTIONS]
    out.update({
        "share_10": rows.share_10.mean(), "share_10_last": last.share_10.mean(),
        "share_10_first_rev": rows[rows.revolutions < rows.revolutions.min() + 1.0].share_10.mean(),
        "d50_particles": rows.d50_particles.mean(), "largest": int(rows.largest.max()),
        "survival": rows.survival.mean(), "comove_ratio": rows.comove_ratio.mean(),
        "slope_per_s": slope.slope, "slope_low": slope.low, "slope_high": slope.high,
        "spanning_frames": rows.spanning.astype(float).mean(),
        "wall_share": rows.wall_share.mean(), "bed_wall_share": rows.bed_wall_share.mean(),
        "wet_share_start": float(flows.sort_values("time").wet_share.iloc[0]),
        "wet_share_end": float(flows.sort_values("time").wet_share.iloc[-1]),
        "angle_deg": flows[flows.time >= SETTINGS.hold_time].angle_of_repose.mean(),
        "revolutions": float(rows.revolutions.max())})
    ok = status == "done"
    out["exists"] = bool(ok and out["share_10"] >= criteria.min_share)
    out["survives"] = bool(ok and np.isfinite(out["survival"])
                           and out["survival"] >= criteria.survival)
    out["grows"] = bool(ok and np.isfinite(out["slope_low"]) and out["slope_low"] > 0.0)
    out["comoves"] = bool(ok and np.isfinite(out["comove_ratio"])
                          and out["comove_ratio"] <= criteria.comove_ratio)
    # amendment 1: a bed bound into one wet mass that spans the slice is not granules
    out["wet_mass"] = bool(out["spanning_frames"] > criteria.spanning_frames)
    out["points"] = 0 if out["wet_mass"] else int(sum(out[p] for p, _ in POINTS))
    return out


def ranked(table: pd.DataFrame) -> pd.DataFrame:
    """The registered pick: most points, ties to the larger share_10 over the last 10
    revolutions."""
    t = table.copy()
    t["share_10_last"] = t.get("share_10_last", pd.Series(np.nan, index=t.index))
    t = t.sort_values(["points", "share_10_last"], ascending=[False, False],
                      na_position="last").reset_index(drop=True)
    t["rank"] = np.arange(1, len(t) + 1)
    return t


def readme(cond: pd.DataFrame) -> str:
    lines = ["# Granule screen, phase 1 (issue 47 item 3)", "",
             "Registered before the runs: [criterion.md](criterion.md). Made by:", "", "```",
             "bash scripts/granule_screen.sh runs",
             ".venv/bin/python scripts/granule_screen_results.py runs/granule_screen", "```",
             "", "Tables: `growth_rows.csv` (every start frame of every run), `conditions.csv` "
             "(one row per condition, its registered points and rank). This README is written "
             "from them by `scripts/granule_screen_results.py` and checked by "
             "`tests/report/test_committed_granule_screen.py`.", "",
             f"Held granules: bridges present through W = {SETTINGS.hold_time:g} s sampled "
             f"every {SETTINGS.cadence:g} s; start frames every {SETTINGS.stride:g} s from "
             f"{SETTINGS.start_after:g} s; granules of >= {SETTINGS.min_particles} particles.",
             "", "## Points (one seed each; criterion.md's phase-1 pick)", "",
             "| rank | condition | model | liquid | status | " + " | ".join(
                 f"{p} ({t})" for p, t in POINTS) + " | points |",
             "|---|---|---|---|---|" + "---|" * len(POINTS) + "---|"]
    for _, r in cond.iterrows():
        lines.append(f"| {int(r['rank'])} | {r.condition} | {r.model} | {r.liquid} | "
                     f"{r.status} | " + " | ".join("yes" if r[p] else "no" for p, _ in POINTS)
                     + f" | {int(r.points)}"
                     + (" (0: spans the slice, a wet mass; amendment 1)" if r.wet_mass else "")
                     + " |")
    lines += ["", "## Measures", "",
              "| condition | share_10 (mean / first rev / last 10 rev) | slope [1/s] (95 %) | "
              "survival | co-movement | d50 [particles] | largest | spanning frames | wall "
              "share (bed) | wet share start / end | angle [deg] | core-min |",
              "|---|---|---|---|---|---|---|---|---|---|---|---|"]
    for _, r in cond.iterrows():
        lines.append(
            f"| {r.condition} | {number(r.get('share_10'))} / "
            f"{number(r.get('share_10_first_rev'))} / {number(r.get('share_10_last'))} | "
            f"{number(r.get('slope_per_s'))} [{number(r.get('slope_low'))}, "
            f"{number(r.get('slope_high'))}] | {number(r.get('survival'))} | "
            f"{number(r.get('comove_ratio'))} | {number(r.get('d50_particles'))} | "
            f"{number(r.get('largest'))} | {number(r.get('spanning_frames'))} | "
            f"{number(r.get('wall_share'))} ({number(r.get('bed_wall_share'))}) | "
            f"{number(r.get('wet_share_start'))} / {number(r.get('wet_share_end'))} | "
            f"{number(r.get('angle_deg'))} | {number(r.core_minutes)} |")
    best = cond.iloc[0]
    total = float(cond.core_minutes.sum())
    lines += ["", f"Best by the registered rule: **{best.condition}** ({best.model}, "
              f"{best.liquid}), {int(best.points)} of {len(POINTS)} points. Phase 1 used "
              f"{total:.0f} core-minutes of the 480 budgeted for the item (cores x wall of "
              "each run, on a machine shared with other work).", ""]
    return "\n".join(lines)


def main() -> int:
    args = parser(__doc__, "granule-screen").parse_args()
    if args.check:
        return write_or_check(OUT, lambda: readme(pd.read_csv(OUT / "conditions.csv")), True,
                              "scripts/granule_screen_results.py")
    all_rows, table = [], []
    for name in CONDITIONS:
        case = case_folder(args.study, name)
        if case is None:
            continue
        status, core_s = status_of(case)
        rows, _, flows = measure_case(case, SETTINGS, cadences=(SETTINGS.cadence,))
        rows.insert(0, "condition", name)
        all_rows.append(rows)
        table.append(condition_row(name, rows, flows, status, core_s))
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / "growth_rows.csv").write_text(csv_text(pd.concat(all_rows)))
    (OUT / "conditions.csv").write_text(csv_text(ranked(pd.DataFrame(table))))
    return write_or_check(OUT, lambda: readme(pd.read_csv(OUT / "conditions.csv")), False,
                          "scripts/granule_screen_results.py")


if __name__ == "__main__":
    sys.exit(main())
