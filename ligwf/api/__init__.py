"""The Python API: a finished study's tables, settings, paths and plots in one object.

A notebook user asks for what a study measured by its meaning, never by a file name::

    import ligwf
    s = ligwf.open_study("runs/demo")
    s.verdict                        # per sweep group, CG level, rule and criterion
    s.conditions[["cg", "rule", "speedup_core", "angle_error", "angle_error_vs_floor"]]
    s.plot_pareto()                  # error vs run cost, returns the matplotlib Axes

Every table is read from the study folder on first use (then cached; each access returns
a copy, so editing one never changes the next), from the file :mod:`ligwf.study.layout`
names for it (``TABLES``: attribute, file, the command that writes it). A table that is
not there is one line naming the command that writes it (:class:`MissingOutput`, a
:class:`~ligwf.errors.LigwfError`), never a traceback; granule tables of a study that has
no granule data by design (a dry scene, ``scene.analysis.contact_dumps: false``) say why.

Dtypes, the same in every table: numbers are ``float64`` (``int64`` where a column is a
count or an index that is never missing), flags are pandas' nullable ``boolean``, text
(case ids, rules, groups, statuses, reasons, floor sources and marks) is pandas' ``string``
dtype -- never ``object`` -- and a text column stays ``string`` when every value is
missing (a ``reason`` column of frames that were all fine). Errors against CG1 are
fractions (0.05 = 5 %), times in seconds, lengths in metres, volumes in m^3 (SI, as in
the study's tables; the report shows them in readable units).

This package is the top layer (``tests/test_architecture.py``): it may import any stage,
and ``ligwf`` itself imports it only lazily, when ``ligwf.open_study`` is first asked for.
"""

from __future__ import annotations

from ligwf.api.results import StudyResults, open_study
from ligwf.api.tables import TABLES, MissingOutput, TableSpec

__all__ = ["MissingOutput", "StudyResults", "TABLES", "TableSpec", "open_study"]
