"""What the analysis stage hands on: its typed records, their readers, and the statistics
of recorded series.

The report (and a notebook) reads the analysis through this package only: the metric
specifications (:mod:`.metrics`), the flow record with each case's steady window and
per-frame series (:mod:`.flow`), the statistic vocabulary a metric is summarised with
(:mod:`.statistics`) and the bootstrap intervals over recorded series (:mod:`.intervals`).
Nothing here reads a dump or computes a granule.
"""
