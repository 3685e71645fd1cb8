"""docs/results/layer_resolution/: the flowing layer's thickness on real frames, read by the
former estimator and by today's (issue 44 item 1).

The former estimator measured from the fitted free surface down to the zero crossing of the
downhill velocity interpolated between depth-bin centres: the surface is fitted to strip
tops, which sit further above the grains' centres the coarser the grains, so the thickness
grew with the grain size on synthetic beds of one flow
(tests/analysis/flow/test_layer_resolution.py). Today's estimator
(:func:`ligwf.analysis.flow.frame.frame_flow`) takes the crossing at the bins' mean particle
depths and the mass-equivalent thickness (the layer's grain volume over the bed's own
packing). This script reads the steady frames of analysed studies (the flow record's steady
window, at most ``--frames`` evenly spaced frames a case) with both, writes ``frames.csv``
(per case: both estimators' mean thickness), derives ``levels.csv`` (per study, rule and
level: the means over runs and each level's difference from the study's finest level, under
both) and renders README.md from them (a ResultsFolder: ``--check`` recomputes both).

    .venv/bin/python scripts/layer_resolution.py runs/liquid_spreading runs/paper_scale_cg
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

import numpy as np
import pandas as pd

from ligwf.analysis.flow import frame as fl
from ligwf.analysis.flow.surface import fit_surface
from ligwf.analysis.frames.dumps import discover_frames, read_particles
from ligwf.analysis.records.flow import FlowRecord
from ligwf.api.results_folder import ResultsFolder, csv_text, number, results_command
from ligwf.scene.grains import scaled_mean_diameter, study_strip
from ligwf.study import layout
from ligwf.study.case import CaseFolder

ROOT = Path(__file__).resolve().parents[1]
OUT = ROOT / "docs" / "results" / "layer_resolution"
#: the table this script measures and the one derived from it (named here, once)
FRAMES, LEVELS = "frames.csv", "levels.csv"


def former_thickness(frame, geo: fl.DrumGeometry) -> float:
    """The estimator before issue 44's fix (kept as the size-dependent reference): from the
    fitted surface down to the zero crossing interpolated between bin centres; nan where it
    found no layer."""
    u, v, vu, vv = fl.cross_section(frame, geo)
    side = fl.rising_side(geo)
    s = fit_surface(u, v, frame.radii, geo.radius, geo.d_mean, side, strip=geo.strip)
    if s is None:
        return float("nan")
    t = np.radians(s.tangent_deg)
    x, y = u * np.cos(t) + v * np.sin(t), -u * np.sin(t) + v * np.cos(t)
    depth = s.offset + geo.radius
    near = np.abs(x) < fl.PROFILE_HALF_WIDTH * geo.radius
    xi = np.clip((s.offset - y[near]) / depth, 0.0, 1.0 - 1e-12)
    down = -side * (vu[near] * np.cos(t) + vv[near] * np.sin(t))
    idx = (xi * fl.PROFILE_BINS).astype(int)
    cnt = np.bincount(idx, minlength=fl.PROFILE_BINS)
    prof = np.where(cnt > 0, np.bincount(idx, down, fl.PROFILE_BINS) / np.maximum(cnt, 1),
                    np.nan)
    centres = (np.arange(fl.PROFILE_BINS) + 0.5) / fl.PROFILE_BINS
    filled = np.flatnonzero(np.isfinite(prof))
    if len(filled) < 2 or prof[filled[0]] <= 0:
        return float("nan")
    below = filled[prof[filled] <= 0]
    if not len(below):
        return float("nan")
    k = below[0]
    a = filled[filled < k][-1]
    zero = centres[a] + (centres[k] - centres[a]) * prof[a] / (prof[a] - prof[k])
    return float(zero * depth)


def case_rows(study: Path, most_frames: int) -> list[dict]:
    """Per case of an analysed study: both estimators' mean thickness over its steady
    frames (the flow record's window), at most ``most_frames`` of them."""
    record = FlowRecord.read(study / layout.ANALYSIS_DIR / layout.FLOW_PROFILES)
    cases = {cid: CaseFolder.open(study / cid) for cid in sorted(record.cases)}
    strip = study_strip([scaled_mean_diameter(c.scaled) for c in cases.values()])
    rows = []
    for cid, case in cases.items():
        flow = record.cases[cid]
        steps = [f for f in discover_frames(case.path)
                 if f.step >= (flow.steady_from_step or 0)]
        pick = np.unique(np.linspace(0, len(steps) - 1, min(most_frames, len(steps)))
                         .round().astype(int)) if steps else []
        geo = fl.DrumGeometry.from_scaled(case.scaled, strip)
        new, old = [], []
        for k in pick:
            frame = read_particles(steps[k].particles, steps[k].step)
            new.append(fl.frame_flow(frame, geo).flowing_layer_thickness)
            old.append(former_thickness(frame, geo))
        rows.append({"study": study.name, "case_id": cid, "cg": case.cg, "rule": case.rule,
                     "d_mm": 1e3 * scaled_mean_diameter(case.scaled), "frames": len(pick),
                     "former_mm": 1e3 * float(np.nanmean(old)) if len(old) else np.nan,
                     "today_mm": 1e3 * float(np.nanmean(new)) if len(new) else np.nan})
    return rows


def levels(frames: pd.DataFrame) -> pd.DataFrame:
    """Per study, rule and level: mean thickness over runs under both estimators and each
    level's difference from the study's finest level (its CG1 when it ran)."""
    out = []
    for study, s in frames.groupby("study", sort=False):
        finest = s[s.cg == s.cg.min()]
        ref_old, ref_new = finest.former_mm.mean(), finest.today_mm.mean()
        for (cg, rule), g in s.groupby(["cg", "rule"], sort=True):
            out.append({"study": study, "cg": cg, "rule": rule, "runs": len(g),
                        "d_mm": g.d_mm.iloc[0], "reference_cg": float(finest.cg.iloc[0]),
                        "former_mm": g.former_mm.mean(), "today_mm": g.today_mm.mean(),
                        # the null beside each difference: how far runs of one level spread
                        "former_sd_mm": g.former_mm.std(ddof=1),
                        "today_sd_mm": g.today_mm.std(ddof=1),
                        "former_minus_finest_mm": g.former_mm.mean() - ref_old,
                        "today_minus_finest_mm": g.today_mm.mean() - ref_new,
                        "moved_mm": g.today_mm.mean() - g.former_mm.mean()})
    return pd.DataFrame(out)


def derived(folder: ResultsFolder) -> dict[str, str]:
    return {LEVELS: csv_text(levels(folder.table(FRAMES)))}


def readme(folder: ResultsFolder) -> str:
    lv = folder.table(LEVELS)
    lines = ["# The flowing layer on real frames, former and today's estimator (issue 44 "
             "item 1)", "", "Made by:", "", "```",
             ".venv/bin/python scripts/layer_resolution.py " + " ".join(
                 f"runs/{s}" for s in dict.fromkeys(lv.study)), "```", "",
             f"`{FRAMES}`: per run, the mean thickness over its steady frames (the analysis' "
             "window, at most 40 evenly spaced frames) under the former estimator (from the "
             "fitted surface to the velocity's zero crossing between bin centres) and "
             "today's (the crossing at the bins' mean depths, the thickness mass-equivalent: "
             f"no surface in it). `{LEVELS}` is derived from it. Synthetic beds of one flow "
             "at 1-3 mm grains (`tests/analysis/flow/test_layer_resolution.py`) show why: the "
             "former read the surface's height above the grains into the layer.", "",
             "The null beside each difference: the seed-to-seed standard deviation of the "
             "runs of each level (3 seeds a level), under each estimator.", "",
             "| study | CG | rule | runs | d [mm] | former [mm] (sd) | today [mm] (sd) | moved [mm] | "
             "former - finest [mm] | today - finest [mm] |",
             "|---|---|---|---|---|---|---|---|---|---|"]
    for _, r in lv.iterrows():
        lines.append(f"| {r.study} | {r.cg:g} | {r.rule} | {int(r.runs)} | {number(r.d_mm)} | "
                     f"{number(r.former_mm)} ({number(r.former_sd_mm, 2)}) | "
                     f"{number(r.today_mm)} ({number(r.today_sd_mm, 2)}) | {number(r.moved_mm, 2)} | "
                     f"{number(r.former_minus_finest_mm, 2)} | "
                     f"{number(r.today_minus_finest_mm, 2)} |")
    coarse = lv[lv.cg > lv.reference_cg]
    if len(coarse):
        shrink = int((coarse.today_minus_finest_mm.abs()
                      < coarse.former_minus_finest_mm.abs()).sum())
        lines += ["", f"In {shrink} of {len(coarse)} coarser levels the difference from the "
                  "study's finest level is smaller under today's estimator than under the "
                  "former one; today's moves every level by "
                  f"{number(lv.moved_mm.min(), 2)} to {number(lv.moved_mm.max(), 2)} mm."]
    return "\n".join(lines) + "\n"


FOLDER = ResultsFolder(OUT, readme, "scripts/layer_resolution.py STUDY ...", derived)


def make(args) -> ResultsFolder:
    if not args.study:
        args.error("at least one analysed study folder is required (or --check)")
    rows = [r for s in [args.study, *args.more] for r in case_rows(s, args.frames)]
    OUT.mkdir(parents=True, exist_ok=True)
    (OUT / FRAMES).write_text(csv_text(pd.DataFrame(rows)))
    return FOLDER


def arguments(ap: argparse.ArgumentParser) -> None:
    ap.add_argument("more", nargs="*", type=Path, help="more analysed study folders")
    ap.add_argument("--frames", type=int, default=40, help="frames a case at most")


def main(argv=None) -> int:
    return results_command(__doc__, [FOLDER], make, argv, arguments)


if __name__ == "__main__":
    sys.exit(main())
