"""docs/results/paper_scale/: the source study's own drum (0.2 m, 360,000 beads of 1 mm at
CG1, D/d = 200) decided without CG1 (issue 44 item 4).

Copies the reported tables of the two background studies (`ligwf report` wrote them: the
verdict against the CG1 value extrapolated from the Weber levels, the extrapolation table,
the cases) and writes `claims.csv`: the source's two flow claims answered at its own scale
from the same case tables (Weber against Bond at each level both ran: the angle of repose,
the rigid-block share, and the share of frames in which one granule holds most of the bed,
with Welch's 95 % interval of the difference over runs) from the copied case tables.
`--check` recomputes `claims.csv` from the committed case tables and compares.

    .venv/bin/python scripts/paper_scale_results.py [RUNS] [--check]    # RUNS: runs/
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

from ligwf.api.results_folder import ResultsFolder, csv_text, results_command
from ligwf.inference.equivalence import difference_estimate, mean_estimate
from ligwf.inference import extrapolation as ex
from ligwf.inference.reference import level_values, slope_scale
from ligwf.study import layout

ROOT = Path(__file__).resolve().parent.parent
OUT = ROOT / "docs/results/paper_scale"
#: the two background studies (run folders in RUNS), by rule
STUDIES = {"weber": "paper_scale_cg", "bond": "paper_scale_cg_bond"}
#: report files copied per study, as <rule>_<name>
COPIED = (layout.CASES_REPORT, layout.CONDITIONS_REPORT, layout.VERDICT_TABLE,
          layout.EXTRAPOLATION_REPORT, layout.SUMMARY_REPORT)
#: the source's claims answered from the copied case tables (derived)
CLAIMS_TABLE = "claims.csv"
#: the claims' metrics: (column, what it says)
CLAIMS = (("angle_of_repose", "angle of repose (deg)"),
          ("rigid_frame_share", "share of frames turning as a rigid block"),
          ("largest_cluster_fraction", "largest connected cluster, share of the bed"),
          ("one_granule_frame_share", "share of frames where one granule holds most of the bed"))


def claims(we: pd.DataFrame, bo: pd.DataFrame) -> pd.DataFrame:
    """Per CG level both rules ran and per claim metric: Bond - Weber over runs."""
    rows = []
    for cg in sorted(set(we["cg"]) & set(bo["cg"])):
        for column, what in CLAIMS:
            if column not in we or column not in bo:
                continue
            x = pd.to_numeric(bo.loc[bo["cg"] == cg, column], errors="coerce").dropna()
            y = pd.to_numeric(we.loc[we["cg"] == cg, column], errors="coerce").dropna()
            if not len(x) or not len(y):
                continue
            d = difference_estimate(x.to_numpy(), y.to_numpy(), alpha=0.025)
            mb, mw = mean_estimate(x.to_numpy(), 0.025), mean_estimate(y.to_numpy(), 0.025)
            rows.append(dict(cg=cg, metric=column, what=what, bond=mb.value, bond_lo=mb.lo,
                             bond_hi=mb.hi, weber=mw.value, weber_lo=mw.lo, weber_hi=mw.hi,
                             bond_minus_weber=d.value, lo=d.lo, hi=d.hi,
                             bond_runs=len(x), weber_runs=len(y),
                             differs=bool(d.has_interval and (d.lo > 0 or d.hi < 0))))
    # both rules target the same CG1: their extrapolated CG1 angles, and their difference
    ratio = 0.001 / 0.2
    fits = {rule: ex.extrapolate(level_values(t, "angle_of_repose"), ratio, 0.025,
                                 slope_scale=slope_scale("angle_of_repose", ratio))
            for rule, t in (("weber", we), ("bond", bo))}
    d = ex.disagreement(fits["bond"], fits["weber"], 0.025)
    rows.append(dict(cg=1.0, metric="extrapolated_cg1_angle",
                     what="CG1 angle of repose extrapolated from each rule's levels (deg; "
                          f"weber {fits['weber'].form}, bond {fits['bond'].form})",
                     bond=fits["bond"].value, bond_lo=fits["bond"].lo, bond_hi=fits["bond"].hi,
                     weber=fits["weber"].value, weber_lo=fits["weber"].lo,
                     weber_hi=fits["weber"].hi, bond_minus_weber=d.value, lo=d.lo, hi=d.hi,
                     bond_runs=int(sum(fits["bond"].replicas)),
                     weber_runs=int(sum(fits["weber"].replicas)),
                     differs=bool(d.has_interval and (d.lo > 0 or d.hi < 0))))
    return pd.DataFrame(rows)


def derived(folder: ResultsFolder) -> dict[str, str]:
    """claims.csv from the committed case tables of both rules."""
    cases = {rule: folder.table(f"{rule}_{layout.CASES_REPORT}") for rule in STUDIES}
    return {CLAIMS_TABLE: csv_text(claims(cases["weber"], cases["bond"]))}


FOLDER = ResultsFolder(OUT, None, "scripts/paper_scale_results.py RUNS", derived)
#: the same studies' tables after their first 1.5 revolutions of production, before
#: `--extend-production 4.5` (as committed in 4edc574; claims.csv recomputes from them too)
FIRST = ResultsFolder(OUT / "first_windows", None,
                      "scripts/paper_scale_results.py RUNS (before --extend-production)",
                      derived)
#: after `--extend-production 4.5` (3 revolutions; as committed in 674d44a), before the
#: Weber study's `--extend-production 13.5` (its Bond twin was not extended again)
THIRD = ResultsFolder(OUT / "three_revolutions", None,
                      "scripts/paper_scale_results.py RUNS (after --extend-production 4.5)",
                      derived)


def make(args) -> ResultsFolder:
    """Copy both studies' report files from RUNS (default runs/)."""
    runs = args.study or ROOT / "runs"
    for rule, folder in STUDIES.items():
        FOLDER.copy_report(runs / folder, COPIED, prefix=f"{rule}_")
    return FOLDER


def main(argv=None) -> int:
    return results_command(__doc__, [FOLDER, THIRD, FIRST], make, argv)


if __name__ == "__main__":
    sys.exit(main())
