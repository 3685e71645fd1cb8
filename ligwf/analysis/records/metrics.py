"""What a reader needs to know about a metric: its column, label, series, statistic, range.

A flow metric is registered once in :mod:`ligwf.analysis.flow.registry` (its per-frame
function and this specification); the analysis writes the specifications of every
registered metric into the flow record, so the report builds its case and condition
tables, intervals, noise floors and CG1 errors from the record and needs no list of its
own. The granule metrics below are the report's quantities from the granule frame table
(the largest granule per frame), summarised the same way.
"""

from __future__ import annotations

import math
from dataclasses import asdict, dataclass

from ligwf.analysis.records import statistics as st

UNIT = (0.0, 1.0)
POSITIVE = (0.0, math.inf)
UNBOUNDED = (-math.inf, math.inf)
#: the markdown tables of the report that can show a metric
CASE_TABLE, CONDITION_TABLE = "cases", "conditions"


@dataclass(frozen=True)
class MetricSpec:
    """One metric of the report tables.

    ``name``: its column in the case and condition tables (with ``_lo``, ``_hi``, ``_se``
    for the interval); ``series``: the per-frame series of the steady window it is
    computed from; ``statistic``: a name of :mod:`ligwf.analysis.records.statistics` (a
    frame statistic, or an error against the CG1 cases of the sweep group, which also
    gets the CG1 noise floor); ``bounds``: the quantity's range (intervals stay inside);
    ``threshold``: of ``share_above``; ``tables``: the markdown tables that show it (every
    metric is in the CSV tables); ``condition_label``: a shorter header in the condition
    table. ``unit`` (SI, as the data dictionary writes units: ``1`` for a ratio or share),
    ``meaning`` and ``shown`` (the unit the report prints, empty: ``unit``) are the metric's
    entry in the data dictionary (:mod:`ligwf.report.dictionary` reads them from the
    registry, so a new metric is documented where it is declared); they are not stored in
    the flow record.
    """

    name: str
    label: str
    series: str
    statistic: str = st.MEAN
    bounds: tuple[float, float] = UNBOUNDED
    threshold: float | None = None
    tables: tuple[str, ...] = (CASE_TABLE, CONDITION_TABLE)
    condition_label: str | None = None
    unit: str = ""
    meaning: str = ""
    shown: str = ""

    def __post_init__(self) -> None:
        if self.statistic not in st.FRAME_STATISTICS + st.ERROR_STATISTICS:
            raise ValueError(f"metric {self.name}: unknown statistic {self.statistic!r}")
        if self.statistic == st.SHARE_ABOVE and self.threshold is None:
            raise ValueError(f"metric {self.name}: share_above needs a threshold")

    @property
    def is_error(self) -> bool:
        """An error against the CG1 reference (not a per-case value of its own)."""
        return self.statistic in st.ERROR_STATISTICS

    def over_frames(self):
        """The statistic over the frame axis of bootstrap draws."""
        return st.over_frames(self.statistic, self.threshold)

    def value(self, series) -> float:
        """The per-case value from one run's series."""
        return st.value(self.statistic, series, self.threshold)

    def header(self, table: str) -> str:
        return (self.condition_label or self.label) if table == CONDITION_TABLE else self.label

    def to_json(self) -> dict:
        d = {k: v for k, v in asdict(self).items() if k not in DOCUMENTATION}
        d["bounds"] = [None if math.isinf(b) else b for b in self.bounds]
        d["tables"] = list(self.tables)
        return d

    @classmethod
    def from_json(cls, d: dict) -> "MetricSpec":
        lo, hi = d.get("bounds") or (None, None)
        return cls(**{**d, "bounds": (-math.inf if lo is None else float(lo),
                                      math.inf if hi is None else float(hi)),
                      "tables": tuple(d.get("tables", ()))})


#: the fields of a MetricSpec that document it (the data dictionary's), not stored with data
DOCUMENTATION = ("unit", "meaning", "shown")
#: the granule metrics' meanings (their data dictionary entries)
LARGEST_MEANING = (
    "share of the bed in the largest granule, mean over the steady frames")
ONE_GRANULE_MEANING = (
    "share of steady frames in which one granule holds more than 99 % of the bed")
#: a frame where one granule holds more than this share of the bed
ONE_GRANULE = 0.99
#: the granule frame table's series (largest granule's share of the bed per frame)
LARGEST_SERIES = "largest"
GRANULE_METRICS = (
    MetricSpec("largest_cluster_fraction", "largest cluster", LARGEST_SERIES, st.MEAN, UNIT,
               unit="1", meaning=LARGEST_MEANING),
    MetricSpec("one_granule_frame_share", "one-granule frames", LARGEST_SERIES, st.SHARE_ABOVE,
               UNIT, threshold=ONE_GRANULE, tables=(), unit="1", meaning=ONE_GRANULE_MEANING),
)
