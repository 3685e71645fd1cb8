"""docs/results/resolution/: how far each flow metric moves on real frames between each
case's own resolution (`analysis.surface_strip = 0`: strips twice the case's diameter) and
the study's one resolution (the default: twice its coarsest level's diameter), issue 44
item 1.

Reads two analyses of the same runs (the study folder and a hard-linked copy whose
study.json says `surface_strip: 0`, analysed again) and writes one row per case and metric.

    cp -rl runs/S runs/S_perlevel && rm -r runs/S_perlevel/{analysis,report}
    (set "surface_strip": 0.0 in runs/S_perlevel/study.json's analysis), ligwf analyse it
    .venv/bin/python scripts/resolution_shift.py runs/S runs/S_perlevel docs/results/resolution/S.csv
"""

from __future__ import annotations

import sys
from pathlib import Path

import pandas as pd

METRICS = ("angle_of_repose", "rigid_frame_share", "flowing_layer_thickness_mean",
           "steady_fraction")


def shifts(fixed: Path, perlevel: Path) -> pd.DataFrame:
    a = pd.read_csv(fixed / "analysis" / "flow.csv")
    b = pd.read_csv(perlevel / "analysis" / "flow.csv")
    rows = []
    for _, r in a.merge(b, on="case_id", suffixes=("_fixed", "_perlevel")).iterrows():
        for m in METRICS:
            rows.append(dict(case_id=r["case_id"], cg=r["cg_fixed"], rule=r["rule_fixed"],
                             metric=m, fixed=r[f"{m}_fixed"], per_level=r[f"{m}_perlevel"],
                             shift=r[f"{m}_fixed"] - r[f"{m}_perlevel"]))
    return pd.DataFrame(rows)


if __name__ == "__main__":
    fixed, perlevel, out = (Path(a) for a in sys.argv[1:4])
    shifts(fixed, perlevel).to_csv(out, index=False, float_format="%.6g")
    print(f"wrote {out}")
