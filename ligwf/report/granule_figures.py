"""Report figures of the granule analysis: granulation kinetics and definition sensitivity.

Read from the analysis folder (:mod:`ligwf.analysis.gsd.kinetics` writes the tables):
``kinetics_summary.csv`` -> granule count, d50, largest granule and bed share in granules
against time, one line per condition with its band over replicas; ``sensitivity.csv`` ->
granule count, d50 and largest granule under each variant of the definition.
"""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from ligwf.study import layout

KINETICS_PANELS = [("granules", "granules (count)"), ("d50", "d50 [mm]"),
                   ("largest_granule", "largest granule [bed share]"),
                   ("granule_share", "bed share in granules")]
SENSITIVITY_PANELS = [("granules", "granules (count)"), ("d50", "d50 [mm]"),
                      ("largest_granule", "largest granule [bed share]")]


def _read(path: Path) -> pd.DataFrame:
    if not path.is_file() or path.stat().st_size <= 1:
        return pd.DataFrame()
    try:
        return pd.read_csv(path)
    except pd.errors.EmptyDataError:
        return pd.DataFrame()


def kinetics_figure(summary: pd.DataFrame, out: Path) -> Path:
    """Kinetics panels against time (s); d50 in mm; bands: 95 % over replicas."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(KINETICS_PANELS), figsize=(4 * len(KINETICS_PANELS), 3.2))
    for ax, (q, label) in zip(axes, KINETICS_PANELS):
        scale = 1e3 if q == "d50" else 1.0
        for name, d in summary.groupby("condition"):
            d = d.sort_values("time")
            line, = ax.plot(d["time"], d[q] * scale, label=name)
            ax.fill_between(d["time"], d[f"{q}_lo"] * scale, d[f"{q}_hi"] * scale,
                            color=line.get_color(), alpha=0.2)
        ax.set_xlabel("time [s]")
        ax.set_ylabel(label)
    axes[0].legend(fontsize=7)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def sensitivity_figure(table: pd.DataFrame, out: Path) -> Path:
    """One bar per variant of the definition and panel; the first bar is the setting used."""
    import matplotlib
    matplotlib.use("Agg")
    import matplotlib.pyplot as plt

    fig, axes = plt.subplots(1, len(SENSITIVITY_PANELS),
                             figsize=(4 * len(SENSITIVITY_PANELS), 3.6))
    y = range(len(table))
    for ax, (q, label) in zip(axes, SENSITIVITY_PANELS):
        scale = 1e3 if q == "d50" else 1.0
        ax.barh(list(y), table[q] * scale, color=["k"] + ["C0"] * (len(table) - 1))
        ax.set_yticks(list(y))
        ax.set_yticklabels(table["variant"] if ax is axes[0] else [""] * len(table), fontsize=7)
        ax.invert_yaxis()
        ax.set_xlabel(label)
    fig.suptitle(f"definition sensitivity ({table['case_id'].iloc[0]}, "
                 f"{int(table['frames'].iloc[0])} steady frames)", fontsize=9)
    fig.tight_layout()
    fig.savefig(out, dpi=110)
    plt.close(fig)
    return out


def granule_figures(analysis_dir: Path, fig_dir: Path) -> list[tuple[str, Path]]:
    """(title, path) of the granule figures whose tables exist in ``analysis_dir``."""
    out = []
    kin = _read(Path(analysis_dir) / layout.KINETICS_SUMMARY_TABLE)
    if not kin.empty:
        out.append(("Granulation kinetics", kinetics_figure(kin, fig_dir / layout.FIGURE_KINETICS)))
    sens = _read(Path(analysis_dir) / layout.SENSITIVITY_TABLE)
    if not sens.empty:
        out.append(("Granule definition sensitivity",
                    sensitivity_figure(sens, fig_dir / layout.FIGURE_SENSITIVITY)))
    return out
