"""Measure the regime-map runs of scripts/regime_map.sh with every candidate granule definition.

Usage: .venv/bin/python scripts/regime_map.py runs/regime docs/results/regime
       .venv/bin/python scripts/regime_map.py --verdict-only docs/results/regime
       .venv/bin/python scripts/regime_map.py --check
Writes OUT/controls_rows.csv (one row per run, definition and start frame),
OUT/controls.csv (means per run and definition, with the run's dimensionless numbers) and
OUT/regime_map.png, then OUT/controls_verdict.csv and .md: the committed OUT/controls.csv
judged with the criteria of today's code (ligwf.analysis.granules.control_verdict).
``--verdict-only`` writes only those two (the runs are not needed), ``--check`` compares
them with the committed ones.
"""

from __future__ import annotations

import sys
import time
from pathlib import Path

import pandas as pd

from ligwf.analysis.granules.control_run import control_rows, load_series, summarise
from ligwf.api.results_folder import ResultsFolder, results_command
from ligwf.scene.regime import regime_numbers
from ligwf.study.case import CaseFolder
from ligwf.study.layout import SCENE_FILE

OUT = Path(__file__).resolve().parents[1] / "docs" / "results" / "regime"
#: the tables it measures (the map's own names)
ROWS, SUMMARY = "controls_rows.csv", "controls.csv"
#: what it derives from SUMMARY: the verdict per wet point and definition
VERDICT, VERDICT_PAGE = "controls_verdict.csv", "controls_verdict.md"
FIGURE = "regime_map.png"


def measure(run_root: Path, out: Path) -> None:
    """Measure every finished point of ``run_root`` into ``out``'s tables and figure."""
    out.mkdir(parents=True, exist_ok=True)
    rows, numbers = [], []
    for point in sorted(p for p in run_root.iterdir() if (p / ".done").exists()):
        for case_dir in sorted(d for d in point.iterdir() if (d / SCENE_FILE).exists()):
            t0 = time.perf_counter()
            cached = point / ROWS                       # beside the run: measured once
            if cached.is_file():
                # a cache measured before percolating was renamed percolating_frames
                r = pd.read_csv(cached).rename(columns={"percolating": "percolating_frames"})
            else:
                r = control_rows(load_series(case_dir))
                r.insert(0, "point", point.name)
                r.to_csv(cached, index=False)
            rows.append(r)
            nums = regime_numbers(CaseFolder.open(case_dir).scaled)
            numbers.append({"point": point.name, **nums})
            print(f"{point.name}: {time.perf_counter() - t0:.0f} s", flush=True)
    all_rows = pd.concat(rows, ignore_index=True)
    all_rows.to_csv(out / ROWS, index=False, float_format="%.4g")
    summary = summarise(all_rows.drop(columns=["point"]).assign(case_id=all_rows["point"]))
    summary = summary.rename(columns={"case_id": "point"}).merge(pd.DataFrame(numbers), on="point")
    summary.to_csv(out / SUMMARY, index=False, float_format="%.4g")
    with pd.option_context("display.width", 250, "display.max_columns", 30):
        print(summary.to_string(index=False, float_format=lambda v: f"{v:.3g}"))
    figure(summary, all_rows, out / FIGURE)


#: each wet point and the cohesionless twin it is judged against: the twins (surface tension
#: and viscosity / 1000) are all practically the same bed without cohesion (Bo_g ~ 0.001);
#: each wet point takes the one of nearest viscosity and the same liquid placement
TWIN_OF = {"wet_mu0.001": "twin_mu0.001", "wet_mu0.01": "twin_mu0.001",
           "wet_mu0.1": "twin_mu0.3", "wet_mu0.3": "twin_mu0.3", "wet_mu0.3_lc0.05": "twin_mu0.3",
           "wet_mu0.3_gamma0.072": "twin_mu0.3", "wet_mu0.3_gamma0.072_L2": "twin_mu0.3",
           "placed_mu0.3": "placed_twin_mu0.3", "placed_mu0.001": "placed_twin_mu0.3"}


def pair_verdicts(summary: pd.DataFrame) -> pd.DataFrame:
    """Per wet point and definition: its measures, its twin's and the pre-registered verdict."""
    from ligwf.analysis.granules.control_verdict import criteria

    by = {(r["point"], r["definition"]): r for _, r in summary.iterrows()}
    rows = []
    for (point, d), w in by.items():
        t = by.get((TWIN_OF.get(point, ""), d))
        if t is None:
            continue
        checks = criteria(w.to_dict(), t.to_dict())
        rows.append({"point": point, "twin": TWIN_OF[point], "definition": d,
                     "St_v": w["stokes_viscous_ennis"], "Bo_g": w["bond_granular"],
                     "share_10": w["share_10"], "twin_share_10": t["share_10"],
                     "persist_quarter": w["persist_quarter"],
                     "twin_persist_quarter": t["persist_quarter"],
                     "comove_ratio": w["comove_ratio"], "ari": min(
                         v for v in (w.get("ari_seed", 1.0), w.get("ari_order", 1.0))
                         if pd.notna(v)),
                     "percolating_frames": w["percolating_frames"],
                     **{c.name: c.passed for c in checks},
                     "passes": all(c.passed for c in checks)})
    return pd.DataFrame(rows)


def _mark(passed) -> str:
    """yes / no, or n/a where the criterion does not apply (ARI of a deterministic
    definition)."""
    if passed is None or (isinstance(passed, float) and pd.isna(passed)):
        return "n/a"
    return "yes" if bool(passed) else "no"


def markdown(v: pd.DataFrame) -> str:
    crit = ["granules exist", "beats the twin", "survives", "moves together", "reproducible",
            "no bed-spanning granule"]
    head = ("| point | definition | St_v | Bo_g | share_10 wet / twin | persistence T/4 wet / twin"
            " | co-movement | ARI | percolating frames | " + " | ".join(crit) + " | passes |")
    lines = [head, "|" + "---|" * (9 + len(crit) + 1)]
    f = lambda x: "–" if pd.isna(x) else f"{x:.3g}"
    for _, r in v.iterrows():
        lines.append(f"| {r['point']} | {r['definition']} | {f(r['St_v'])} | {f(r['Bo_g'])} | "
                     f"{f(r['share_10'])} / {f(r['twin_share_10'])} | "
                     f"{f(r['persist_quarter'])} / {f(r['twin_persist_quarter'])} | "
                     f"{f(r['comove_ratio'])} | {f(r['ari'])} | {f(r['percolating_frames'])} | "
                     + " | ".join(_mark(r.get(c)) for c in crit)
                     + f" | {'**yes**' if r['passes'] else 'no'} |")
    return "\n".join(lines) + "\n"


def derived(folder: ResultsFolder) -> dict[str, str]:
    """The verdict of the committed controls.csv, as a table and a page. A table measured
    before 988a134 names St_v,Ennis ``stokes_viscous`` (the map had lubrication off): it
    is read as ``stokes_viscous_ennis``."""
    summary = folder.table(SUMMARY)
    if "stokes_viscous_ennis" not in summary:
        summary = summary.rename(columns={"stokes_viscous": "stokes_viscous_ennis"})
    verdicts = pair_verdicts(summary)
    return {VERDICT: verdicts.to_csv(index=False, float_format="%.4g"),
            VERDICT_PAGE: markdown(verdicts)}


FOLDER = ResultsFolder(OUT, None, "scripts/regime_map.py --verdict-only docs/results/regime",
                       derived)


def figure(summary: pd.DataFrame, rows: pd.DataFrame, path: Path,
           definitions=("held_0.5s", "held_1s", "communities")) -> None:
    """Regime map: share of the bed in granules and their persistence against St_v (wet
    filled, cohesionless twin open; uniform beds circles, placed granules squares), and the
    granule share against time of the placed beds."""
    import matplotlib
    matplotlib.use("Agg", force=True)
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, 3, figsize=(15, 4.4))
    colours = dict(zip(definitions, ("C0", "C1", "C3")))
    for d in definitions:
        sub = summary[summary["definition"] == d]
        for _, r in sub.iterrows():
            twin = "twin" in r["point"]
            placed = r["point"].startswith("placed")
            # a twin is drawn at its wet partner's St_v (its own is 1000x larger)
            st = r["stokes_viscous_ennis"] / (1000.0 if twin else 1.0)
            kw = dict(marker="s" if placed else "o", color=colours[d], ms=7,
                      mfc="none" if twin else colours[d], ls="none")
            axes[0].plot(st, r["share_10"], **kw)
            axes[1].plot(st, r["persist_quarter"], **kw)
        axes[0].plot([], [], "o", color=colours[d], label=d)
    axes[0].plot([], [], "ko", mfc="none", label="cohesionless twin (at its wet St_v)")
    axes[0].plot([], [], "ks", label="placed wet granules")
    for ax, label in zip(axes[:2], ("bed volume in granules of >= 10 particles",
                                    "pair persistence after a quarter revolution")):
        ax.set_xscale("log")
        ax.set_xlabel("viscous Stokes number St_v (CG1)")
        ax.set_ylabel(label)
        ax.set_ylim(-0.02, 1.02)
        ax.grid(alpha=0.3)
    axes[1].axhline(0.5, color="grey", ls=":", lw=1)
    axes[0].legend(fontsize=8, loc="upper right")
    ax = axes[2]
    placed = rows[rows["point"].str.startswith("placed") & (rows["definition"] == definitions[0])]
    for point, sub in placed.groupby("point"):
        ax.plot(sub["time"], sub["share_10"], "-o" if "twin" not in point else "--o",
                ms=3, label=point)
    ax.set_xlabel("time since the drum started, s")
    ax.set_ylabel(f"bed volume in granules ({definitions[0]})")
    ax.set_title("placed wet granules: accretion and erosion")
    ax.grid(alpha=0.3)
    if len(placed):
        ax.legend(fontsize=8)
    fig.tight_layout()
    fig.savefig(path, dpi=110)
    plt.close(fig)


def arguments(ap) -> None:
    ap.add_argument("out", nargs="?", type=Path, default=OUT, help="the results folder")
    ap.add_argument("--verdict-only", action="store_true",
                    help="only judge the committed controls.csv of the folder given")


def make(args) -> ResultsFolder:
    if args.study is None:
        args.error("give the run folder and the results folder (or --verdict-only OUT, "
                   "or --check)")
    if args.verdict_only:
        return ResultsFolder(args.study, None, FOLDER.remake, derived)
    measure(args.study, args.out)
    return ResultsFolder(args.out, None, FOLDER.remake, derived)


def main(argv=None) -> int:
    return results_command(__doc__, [FOLDER], make, argv, arguments)


if __name__ == "__main__":
    sys.exit(main())
