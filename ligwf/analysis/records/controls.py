"""The granule controls table of a study's analysis (``analysis/controls.csv``, written by
:mod:`ligwf.analysis.granules.study_controls`), read for the stages above: the verdict's
granule gates (:mod:`ligwf.inference.verdict_records`) and the report's controls section."""

from __future__ import annotations

from pathlib import Path

import pandas as pd

from ligwf.analysis.records.renamed import current_names
from ligwf.study import layout


def read_controls(analysis_dir: Path) -> pd.DataFrame | None:
    """The controls table, or None when the study has no twins (or no analysis); one
    written by the previous release is read with its current column names
    (:func:`~ligwf.analysis.records.renamed.current_names`)."""
    path = Path(analysis_dir) / layout.CONTROLS_TABLE
    if not path.is_file() or path.stat().st_size == 0:
        return None
    table = current_names(pd.read_csv(path), layout.CONTROLS_TABLE, str(path))
    return table if len(table) else None
