#!/usr/bin/env python3
"""The committed results folders whose runs are kept but not made again: each README is
rendered from a template with its numbers read from the folder's committed tables.

    .venv/bin/python scripts/kept_results.py docs/results/granules   # writes that README
    .venv/bin/python scripts/kept_results.py --check                 # READMEs == tables

Each folder below is a declaration: where it is, the README's template (the prose as it was
written by hand; every number a table holds is a ``{field}``) and the function that reads
those fields from the committed tables, and the tables it recomputes (``derived``).
``--check`` (what the folders' committed-results tests run) renders every README again and
compares it, and each derived table, with the committed file.
"""

from __future__ import annotations

import contextlib
import io
import sys
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
sys.path.insert(0, str(ROOT))

import pandas as pd  # noqa: E402

from benchmarks import bench_null_splits, bench_steady  # noqa: E402
from ligwf.analysis.records.steady_window import at_cap  # noqa: E402
from ligwf.api.results_folder import ResultsFolder, from_template, results_command  # noqa: E402
from ligwf.study import layout  # noqa: E402

RESULTS = ROOT / "docs" / "results"
#: each README's template: the prose as written by hand, ``{field}`` where a table holds
#: the number (scripts/readme_templates/NAME.md for docs/results/NAME)
TEMPLATES = Path(__file__).resolve().parent / "readme_templates"


def kept(name: str, fields, derived=None) -> ResultsFolder:
    """The kept folder docs/results/``name``: its README from its template, filled with
    ``fields(folder)``; ``derived`` the tables it recomputes."""
    return ResultsFolder(RESULTS / name, from_template(TEMPLATES / f"{name}.md", fields),
                         f"scripts/kept_results.py docs/results/{name}", derived)


def _share(x: float) -> str:
    """A fraction as a README's percentage: ``1.0`` -> ``100``, ``0.996`` -> ``99.6``."""
    return f"{100 * x:.3g}"


def _span(values, spec: str) -> str:
    """The smallest and largest of ``values`` as ``lo-hi``, each in ``spec``."""
    return f"{format(min(values), spec)}-{format(max(values), spec)}"


# --------------------------------------------------------------------------- granules


def granules_fields(folder: ResultsFolder) -> dict[str, str]:
    """The granules README's numbers: the second seed's and the first seed's wall times
    (cases), the CG2 speedups and Bond-CG2's field error (verdict), the CG1-vs-CG1 field
    floor (null check)."""
    wall = folder.table(layout.CASES_REPORT).set_index("case_id")["wall_seconds"]
    verdict = folder.table(layout.VERDICT_TABLE)
    field = verdict[verdict["criterion"] == "field_error"].set_index("condition")
    bond = field.loc["cg2-bond"]
    speedups = verdict.groupby("condition")["speedup_core"].first()
    floor = folder.table(layout.FIELD_NULL_REPORT)["field_error_floor"]
    return {"r1_wall": f"{wall['cg1-none-r1']:.0f}",
            "r1_twin_wall": f"{wall['cg1-none-r1_cohesionless']:.0f}",
            "r0_wall": f"{wall['cg1-none-r0']:.0f}",
            "r0_twin_wall": f"{wall['cg1-none-r0_cohesionless']:.0f}",
            "speedups": f"{speedups.min():.0f}-{speedups.max():.0f}",
            "bond_field": f"{bond['value']:.2f} [{bond['lo']:.2f}, {bond['hi']:.2f}]",
            "field_floor": f"{floor.iloc[0]:.2g}",
            "replicas": f"{int(verdict['replicas'].iloc[0])}",
            "controls": layout.CONTROLS_TABLE, "summary": layout.SUMMARY_REPORT,
            "html": layout.HTML_REPORT, "cases": layout.CASES_REPORT,
            "conditions": layout.CONDITIONS_REPORT, "noise_floor": layout.NOISE_FLOOR_REPORT,
            "verdict": layout.VERDICT_TABLE, "verdict_record": layout.VERDICT_RECORD,
            "null_check": layout.FIELD_NULL_REPORT, "figures": layout.FIGURES_DIR}


GRANULES = kept("granules", granules_fields)

# ------------------------------------------------------------------------ null_splits
#: the runs split, as the study wrote them (one row per run)
NULL_CASES = f"{layout.REPORT_DIR}/{layout.CASES_REPORT}"
#: what benchmarks/bench_null_splits.py prints from them, under the command that made it
SPLITS = "splits.txt"
NULL_STUDY = ("ligwf study workflows/demo.yaml --out runs/null8 --set 'sweep.cg_levels=[2]' "
              "--set 'sweep.replicas={2: 8}' --np 1 --no-snapshots")


def null_splits_tables(folder: ResultsFolder) -> dict[str, str]:
    """splits.txt: benchmarks/bench_null_splits.py's output on the committed runs, under
    the command line that made it."""
    out = io.StringIO()
    with contextlib.redirect_stdout(out):
        bench_null_splits.main([str(folder.path)])
    header = (f"# .venv/bin/python benchmarks/bench_null_splits.py docs/results/null_splits   "
              f"(made from: {NULL_STUDY}; {NULL_CASES} copied here)\n")
    return {SPLITS: header + out.getvalue()}


NULL_SPLITS = kept("null_splits", lambda folder: {"study": NULL_STUDY, "cases": NULL_CASES,
                                                  "report": layout.REPORT_DIR,
                                                  "splits": SPLITS},
                   null_splits_tables)

# --------------------------------------------------------------------------- we_vs_bo
#: the tables of the we_vs_bo folder beside its report's: the analysis's and the controls'
WVB_ANALYSIS, WVB_CONTROLS = layout.ANALYSIS_DIR, "controls"
#: the registered granule definition's row of the controls table
WVB_DEFINITION = "study definition (communities)"


def we_vs_bo_rows(conditions: pd.DataFrame) -> str:
    """The report's comparison table, one row per condition (CG1 first, the reference)."""
    def cell(r, column, spec):
        return (f"{format(r[column], spec)} [{format(r[column + '_lo'], spec)}, "
                f"{format(r[column + '_hi'], spec)}]")

    rows = []
    for _, r in conditions.sort_values(["cg", "rule"], ascending=[True, False]).iterrows():
        if r["cg"] == 1:
            name, speedup = f"CG1 ({int(r['replicas'])} replicas)", "1"
            errors = "reference | reference"
        else:
            name = f"{'We' if r['rule'] == 'weber' else 'Bo'}-CG{r['cg']:g}"
            speedup = cell(r, "speedup_core", ".1f")
            errors = (f"{cell(r, 'angle_error', '.3f')} {r['angle_error_vs_floor']} | "
                      f"{cell(r, 'profile_error', '.3f')} {r['profile_error_vs_floor']}")
        rigid = cell(r, "rigid_frame_share", ".2f") if r["rigid_frame_share"] else "0"
        rows.append(f"| {name} | {speedup} | {cell(r, 'angle_of_repose', '.1f')} | {errors} | "
                    f"{r['angle_of_repose_std']:.1f} | {rigid} | "
                    f"{r['rms_speed_rel_fluctuation']:.3f} |")
    return "\n".join(rows)


def we_vs_bo_fields(folder: ResultsFolder) -> dict[str, object]:
    """The we_vs_bo README's numbers: the comparison table and the conclusions' ratios
    (conditions), the CG1 costs (cases), the granule sections (the analysis's frames, flow,
    GSD, pooling and sensitivity tables) and the status note (the controls' tables)."""
    cond = folder.table(layout.CONDITIONS_REPORT)
    c = {("cg1" if r["cg"] == 1 else f"{r['rule'][:2]}{r['cg']:g}"): r
         for _, r in cond.iterrows()}
    cg1, we2, bo2, we3, bo3 = (c[k] for k in ("cg1", "we2", "bo2", "we3", "bo3"))
    cases = folder.table(layout.CASES_REPORT)
    analysis = folder.path / WVB_ANALYSIS
    flow = pd.read_csv(analysis / layout.FLOW_TABLE).set_index("case_id")
    frames = pd.read_csv(analysis / layout.FRAMES_TABLE)
    cg1_ids = list(cases[cases["cg"] == 1]["case_id"])
    steady = pd.concat([frames[(frames["case_id"] == cid)
                               & (frames["step"] >= flow.loc[cid, "steady_from_step"])]
                        for cid in cg1_ids])
    gsd = pd.read_csv(analysis / layout.GSD_SUMMARY_TABLE).set_index("condition")
    pooling = pd.read_csv(analysis / layout.GSD_POOLING_TABLE)
    floor = pooling[pooling["condition"] == "cg1"].iloc[0]
    sens = pd.read_csv(analysis / layout.SENSITIVITY_TABLE).set_index("variant")["d50_ratio"]
    controls = pd.read_csv(folder.path / WVB_CONTROLS / layout.CONTROLS_TABLE)
    held = controls[controls["definition"] == WVB_DEFINITION].iloc[0]
    angle = pd.read_csv(folder.path / WVB_CONTROLS / layout.FLOW_TABLE).set_index(
        "case_id")["angle_of_repose"]
    r0, r1 = (flow.loc[cid] for cid in cg1_ids)
    bond, weber = (bo2, bo3), (we2, we3)
    pair = lambda a, b, spec: f"{format(a, spec)} / {format(b, spec)}"  # noqa: E731
    setup = lambda r: r["fill_core_seconds"] + r["settle_core_seconds"]  # noqa: E731
    return {
        "cg1_particles": f"{int(cg1['particles']):,}",
        "share_10": _share(held["share_10"]), "twin_share_10": _share(held["twin_share_10"]),
        "d50": f"{held['d50_mm']:.1f}", "twin_d50": f"{held['twin_d50_mm']:.1f}",
        "ari": _span((held["ari_seed"], held["ari_order"]), ".2f"),
        "persist": f"{held['persist_quarter']:.2f}",
        "twin_persist": f"{held['twin_persist_quarter']:.2f}",
        "comove": f"{held['comove_ratio']:.2f}",
        "twin_angle": f"{angle[held['twin_id']]:.1f}", "wet_angle": f"{angle[held['case_id']]:.1f}",
        "cg1_replicas": int(cg1["replicas"]), "cgn_replicas": int(we2["replicas"]),
        "cg1_core_s": " and ".join(f"{x:,.0f}" for x in cases[cases["cg"] == 1]["core_seconds"]),
        "angle_floor": f"{cg1['angle_error_floor']:.3f}",
        "profile_floor": f"{cg1['profile_error_floor']:.3f}",
        "condition_rows": we_vs_bo_rows(cond),
        "bond_rigid": f"{100 * bo2['rigid_frame_share']:.0f}",
        "bond_std_ratio": _span([r["angle_of_repose_std"] / cg1["angle_of_repose_std"]
                                 for r in bond], ".1f"),
        "bond_std": _span([r["angle_of_repose_std"] for r in bond], ".1f"),
        "cg1_std": f"{cg1['angle_of_repose_std']:.1f}",
        "weber_std_ratio": _span([r["angle_of_repose_std"] / cg1["angle_of_repose_std"]
                                  for r in weber], ".1f"),
        "angle_ratio2": f"{bo2['angle_error'] / we2['angle_error']:.0f}",
        "angle_ratio3": f"{bo3['angle_error'] / we3['angle_error']:.0f}",
        "profile_ratio2": f"{bo2['profile_error'] / we2['profile_error']:.0f}",
        "profile_ratio3": f"{bo3['profile_error'] / we3['profile_error']:.1f}",
        "bo2_angle": f"{bo2['angle_error']:.3f}", "we2_angle": f"{we2['angle_error']:.3f}",
        "we3_angle": f"{we3['angle_error']:.3f}",
        "bo2_profile": f"{bo2['profile_error']:.3f}", "we2_profile": f"{we2['profile_error']:.3f}",
        "we3_profile": f"{we3['profile_error']:.3f}",
        "bond_rigid_lo": f"{min(r['rigid_frame_share_lo'] for r in bond):.2f}",
        "bond_rigid_hi": f"{max(r['rigid_frame_share_hi'] for r in bond):.2f}",
        "weber_growth": f"{we3['angle_error'] / we2['angle_error']:.1f}",
        "we2_angle_lo": f"{we2['angle_error_lo']:.3f}",
        "we2_profile_lo": f"{we2['profile_error_lo']:.3f}",
        "bo3_angle_deg": f"{bo3['angle_of_repose']:.1f}",
        "cg1_angle_deg": f"{cg1['angle_of_repose']:.1f}",
        "bo3_angle_error": f"{bo3['angle_error']:.2f}",
        "we2_speedup": f"{we2['speedup_core']:.1f}", "bo2_speedup": f"{bo2['speedup_core']:.1f}",
        "we3_speedup": f"{we3['speedup_core']:.0f}", "bo3_speedup": f"{bo3['speedup_core']:.0f}",
        "ideal2": f"{we2['cg'] ** 4:.0f}", "ideal3": f"{we3['cg'] ** 4:.0f}",
        "cg3_setup": f"{setup(we3):.0f}", "cg3_core": f"{we3['core_seconds']:.0f}",
        "cg1_setup": f"{setup(cg1):.0f}", "cg1_core": f"{float(format(cg1['core_seconds'], '.3g')):,.0f}",
        "r0_angle": f"{r0['angle_of_repose']:.2f}", "r0_std": f"{r0['angle_of_repose_std']:.2f}",
        "r0_frames": int(r0["frames"]),
        "r1_angle": f"{r1['angle_of_repose']:.2f}", "r1_std": f"{r1['angle_of_repose_std']:.2f}",
        "r1_frames": int(r1["frames"]),
        "steady_frames": int(gsd.loc["cg1", "frames"]),
        "largest_mean": f"{100 * steady['largest_fraction'].mean():.1f}",
        "largest_max": f"{100 * steady['largest_fraction'].max():.1f}",
        "sens_frames": int(pd.read_csv(analysis / layout.SENSITIVITY_TABLE)["frames"].iloc[0]),
        "sens_range": _span(sens, ".2f"),
        "sens_resolution": pair(sens["resolution x0.8"], sens["resolution x1.25"], ".2f"),
        "sens_angle": pair(sens["angle 24 deg (lab)"], sens["angle 37.5 deg (lab)"], ".2f"),
        "sens_frel": pair(sens["f_rel > 0.4"], sens["f_rel > 0.625"], ".2f"),
        "band": f"{100 * floor['error_band']:.0f}",
        "cg1_limit": f"{floor['upper_limit']:.1e}".replace("e-0", "e-"),
        "cg1_limit_error": f"{floor['error_below_upper']:.3f}",
        "we2_gsd": f"{we2['gsd_error_below']:.2f}", "bo2_gsd": f"{bo2['gsd_error_below']:.2f}",
        "we3_gsd": f"{we3['gsd_error_below']:.2f}", "bo3_gsd": f"{bo3['gsd_error_below']:.2f}",
        **{f"{k}_d50": f"{1e3 * gsd.loc[name, 'd50']:.2f}" for k, name in
           (("cg1", "cg1"), ("we2", "cg2-weber"), ("bo2", "cg2-bond"), ("we3", "cg3-weber"),
            ("bo3", "cg3-bond"))},
    }


WE_VS_BO = kept("we_vs_bo", we_vs_bo_fields)

# ----------------------------------------------------------------------------- steady
#: the benchmark runs (their output, the command on the first line) and the long check's
#: tables, per steady rule (``band``: the rule before, ``mser``: MSER-5 from 80 frames on)
STEADY_BENCH, STEADY_HYBRID = "bench_steady.txt", "bench_steady_hybrid.txt"
STEADY_EXTENSIONS = ("bench_steady_extension.txt", "bench_steady_extension_2.txt")
STEADY_RULES = ("band", "mser")
LONG_CASES, LONG_VERDICT = "long_cases_{}.csv", "long_verdict_{}.csv"
LONG_PREDICTION = "long_prediction_check_mser.csv"
#: registered in the README before each run
HYBRID_CAPPED, HYBRID_BIAS = 0.20, 0.25


def _cells_span(cells: list[dict], key: str, spec: str = ".2f") -> str:
    """:func:`_span` of the benchmark cells' ``key``."""
    return _span([float(c[key]) for c in cells], spec)


def _each(values: list[str]) -> str:
    """``a, b and c``: one value per registered cell, in the file's order."""
    return ", ".join(values[:-1]) + f" and {values[-1]}"


def steady_fields(folder: ResultsFolder) -> dict[str, object]:
    """The steady README's numbers: each benchmark run's cells and hypotheses (its
    committed output), the long check's capped windows, decisions and extension rows."""
    text = (folder.path / STEADY_BENCH).read_text()
    cells = bench_steady.read_cells(text)
    still = [c for c in cells if not c["startup"]]
    at = {n: [c for c in still if c["frames"] == n] for n in (40, 80, 160)}
    said = {True: "holds", False: "does not hold"}
    h = bench_steady.hypotheses(text)
    out = {f"band_{n}": _cells_span(at[n], "current") for n in at}
    out |= {f"mser_{n}": _cells_span(at[n], "mser") for n in at}
    out |= {"h1": said[h["H1"]], "h2": said[h["H2"]],
            "band_low": f"{min(c['current'] for c in at[160]):.2f}",
            "bias": f"{max(max(abs(c['current_bias']), abs(c['mser_bias'])) for c in cells):.2f}"}
    hybrid = bench_steady.read_cells((folder.path / STEADY_HYBRID).read_text())
    long_still = [c for c in hybrid if not c["startup"] and c["frames"] >= 80]
    worst = max(c["current"] for c in long_still)
    bias = max(abs(c["current_bias"]) for c in hybrid)
    out |= {"hybrid_worst": f"{worst:.2f}", "hybrid_bias": f"{bias:.2f}",
            "hybrid_met": "met" if worst <= HYBRID_CAPPED and bias <= HYBRID_BIAS else "not met"}
    out |= {f"hybrid_{n}": _cells_span([c for c in long_still if c["frames"] == n], "current")
            for n in (80, 160)}
    for rule in STEADY_RULES:
        cases = folder.table(LONG_CASES.format(rule))
        verdict = folder.table(LONG_VERDICT.format(rule))
        assessed = verdict[verdict["state"] != "not assessed"]
        out[f"capped_{rule}"] = int(cases["steady_fraction"].map(at_cap).sum())
        out[f"runs_{rule}"] = len(cases)
        out[f"decided_{rule}"] = (f"{int(assessed['state'].isin(['pass', 'fail']).sum())} of "
                                  f"{len(assessed)}")
    check = folder.table(LONG_PREDICTION)
    extension = check[check["kind"] == "extension"]
    out |= {"ext_holds": int(extension["within_30_percent"].sum()),
            "ext_rows": int(extension["measured_over_predicted"].notna().sum())}
    for k, name in enumerate(STEADY_EXTENSIONS, 1):
        text = (folder.path / name).read_text()
        rows = bench_steady.read_extension_cells(text)
        reg = [r for r in rows if r["phi"] == 0.5]          # the registered cells
        beside = [r for r in rows if r["phi"] == 0.8]
        h = bench_steady.hypotheses(text)
        extended = [r["extended"] for r in reg]
        biases = sorted(float(r["bias"]) for r in reg)
        out |= {f"e{k}_before": _cells_span(reg, "before", ".3f"),
                f"e{k}_extended": f"{min(extended)}-{max(extended)}",
                f"e{k}_after": _each([r["after"] for r in reg]),
                f"e{k}_median": _each([r["median"] for r in reg]),
                f"e{k}_late": _each([r["late"] for r in reg]),
                f"e{k}_bias": f"{biases[0]:.2f} to {biases[-1]:.2f}",
                f"e{k}_beside_after": _cells_span(beside, "after", ".3f"),
                f"e{k}_beside_median": _cells_span(beside, "median", ".4f"),
                **{f"e{k}_h{i}": "met" if h[f"H-ext{i}"] else "not met" for i in (1, 2, 3)}}
        if k == 1:
            out["e1_excess"] = f"{float(reg[1]['after']) - bench_steady.EXT_STILL_CAPPED:.3f}"
    return out


STEADY = kept("steady", steady_fields)

FOLDERS = (GRANULES, NULL_SPLITS, WE_VS_BO, STEADY)


def make(args) -> ResultsFolder:
    """The declared folder ``args.study`` names (its README and derived tables are
    written again from its committed tables)."""
    if args.study is None:
        args.error("give a folder (" + ", ".join(str(f.path.relative_to(ROOT))
                                                 for f in FOLDERS) + ") or --check")
    for folder in FOLDERS:
        if args.study.resolve() == folder.path:
            return folder
    args.error(f"{args.study}: not a kept results folder (" + ", ".join(
        str(f.path.relative_to(ROOT)) for f in FOLDERS) + ")")


def main(argv=None) -> int:
    return results_command(__doc__, FOLDERS, make, argv)


if __name__ == "__main__":
    sys.exit(main())
