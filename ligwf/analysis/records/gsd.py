"""The GSD comparison's column names, as the GSD stage writes them and the report reads
them (``gsd_summary.csv``; :mod:`ligwf.analysis.gsd.tables`).

Every GSD error names the limit it is measured against. The relative L1 error of CG-n's
volume-weighted GSD against CG1's is summed over the bins below and above the LOWER size
limit (located from the data: CG-n stays within the error band from it on, so "below" is
the side CG-n does not resolve) and over all bins (no limit). When no lower limit is
located (nan: CG-n never enters the band) every bin is below it, so ``error_below_lower``
equals ``error_all`` and ``error_above_lower`` is nan. The pooling table's upper-limit
errors are ``error_below_upper`` / ``error_above_upper`` (:mod:`ligwf.analysis.gsd.pooling`).
"""

from __future__ import annotations

#: the lower size limit (m^3) of ``gsd_summary.csv`` (with ``_lo`` / ``_hi``)
LOWER_LIMIT = "lower_limit"
#: the GSD errors of ``gsd_summary.csv`` (each with ``_lo`` / ``_hi``), see the module text
GSD_ERRORS = ("error_below_lower", "error_above_lower", "error_all")
