"""The report's "Granule controls" section: the granules beside a bed that should have none.

Reads ``analysis/controls.csv`` (:mod:`ligwf.analysis.granules.study_controls`; it computes
nothing). With twins, a table per wet case of every definition's measures against the
twin's, and the verdict sentence of the study's own definition first; without twins, one
sentence saying that the granules of this study were never checked against a control, and
what the regime map found (docs/results/granule_definitions.md).
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from ligwf.analysis.records.controls import read_controls
from ligwf.study import layout

#: (column, header) of the control table; each is shown as "wet / twin"
COLUMNS = (("share_10", "bed in granules >= 10"), ("count_10", "granules >= 10"),
           ("d50_mm", "d50 [mm]"), ("persist_quarter", "persistence T/4"),
           ("comove_ratio", "co-movement"), ("percolating_frames", "percolating frames"))

NO_CONTROL = ("This study ran no cohesionless control (`sweep.controls: [cohesionless]`), so "
              "its granules were never shown to differ from those of a bed without cohesion. "
              "On the beds measured so far (docs/results/granule_definitions.md) a uniformly "
              "wetted bed had no granules that beat that control under any definition: read "
              "the granule sizes, GSD errors and size limits below as properties of the "
              "definition, not as findings about granulation.")


def _cell(r, col: str) -> str:
    def f(v):
        return "–" if pd.isna(v) else f"{v:.3g}"
    return f"{f(r[col])} / {f(r['twin_' + col])}"


def controls_markdown(analysis_dir: Path) -> list[str]:
    """Markdown lines of the section (always present: without twins it says so)."""
    table = read_controls(analysis_dir)
    lines = ["## Granule controls (wet bed / cohesionless twin)", ""]
    if table is None:
        return lines + [NO_CONTROL, ""]
    for (case_id, _), rows in table.groupby(["case_id", "twin_id"], sort=False):
        own = rows.iloc[0]
        lines += [f"**{case_id}** against `{own['twin_id']}`: {own['verdict']}.", "",
                  "| definition | passes | " + " | ".join(h for _, h in COLUMNS) + " |",
                  "|---|---|" + "---|" * len(COLUMNS)]
        for _, r in rows.iterrows():
            lines.append(f"| {r['definition']} | {'yes' if r['passes'] else 'no'} | "
                         + " | ".join(_cell(r, c) for c, _ in COLUMNS) + " |")
        lines.append("")
    every = table.assign(passes=table["passes"].astype(bool)).groupby(
        "definition", sort=False)["passes"].all()
    passing = [d for d, ok in every.items() if ok]
    lines.append("Definitions that beat every control twin here: "
                 + (", ".join(f"`{d}`" for d in passing) if passing else "none") + ".")
    return lines + [""]
