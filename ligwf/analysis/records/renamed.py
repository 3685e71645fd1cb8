"""Analysis-table columns renamed since the previous ligwf, read under their new names.

Two names had two meanings (issue 33) and were renamed in the tables ``ligwf analyse``
writes:

* flow table: ``angle_of_repose_mean`` (the flow summary's mean of the steady frames'
  angles) was the same number as ``angle_of_repose`` (the registered flow metric, the
  name of the case and condition tables); the table now has ``angle_of_repose`` only.
* controls table: ``percolating`` (and ``twin_percolating``), the share of steady frames
  holding a percolating granule, is now ``percolating_frames`` as in the GSD summary;
  ``percolating`` is only the per-granule flag of the granules table.

An analysis folder written before keeps its old columns until ``ligwf analyse`` runs
again. Its readers (the report's controls section, the API's tables) pass it through
:func:`current_names`, which gives the new names and warns (a ``FutureWarning`` naming
the command that rewrites the table). The old names are read this way for one release.
"""

from __future__ import annotations

import warnings

import pandas as pd

from ligwf.study import layout

#: table file -> {old column: new column}
RENAMED: dict[str, dict[str, str]] = {
    layout.FLOW_TABLE: {"angle_of_repose_mean": "angle_of_repose"},
    layout.CONTROLS_TABLE: {"percolating": "percolating_frames",
                            "twin_percolating": "twin_percolating_frames"},
}


def current_names(table: pd.DataFrame, file: str, where: str = "") -> pd.DataFrame:
    """``table`` (read from the analysis table ``file``) with its columns under their
    current names: an old column is renamed, or dropped where the table also has the new
    one (the flow table of the previous release had both, with equal values). Warns once
    per call when anything was old; ``where`` (the file's path) goes into the warning."""
    old = {o: n for o, n in RENAMED.get(file, {}).items() if o in table.columns}
    if not old:
        return table
    warnings.warn(f"{where or file}: written by an earlier ligwf, read with the columns "
                  + ", ".join(f"{o} -> {n}" for o, n in old.items())
                  + "; run `ligwf analyse` again to rewrite it (the old names are read "
                  "until the next release)", FutureWarning, stacklevel=2)
    both = [o for o, n in old.items() if n in table.columns]
    return table.drop(columns=both).rename(
        columns={o: n for o, n in old.items() if o not in both})
