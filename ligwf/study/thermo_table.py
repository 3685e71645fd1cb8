"""The thermo table of a case folder (``thermo.csv``): one row per thermo line over all
attempts, written by the runner (:mod:`ligwf.engine.attempt`) from the screen it parsed
(:mod:`ligwf.engine.thermo`) and read back by the folder model to check a finished run
(:meth:`ligwf.study.case.CaseFolder.record_hole`) and by the later stages.
"""

from __future__ import annotations

import csv
import io
import math
from dataclasses import dataclass


@dataclass(frozen=True)
class ThermoRow:
    """One thermo line: the step, the values by ligwf column name, and its phase."""

    step: int
    values: dict[str, float]
    phase: str

    def get(self, name: str, default: float = math.nan) -> float:
        return self.values.get(name, default)


#: Columns of the thermo table written next to each run (``thermo.csv``).
TABLE_COLUMNS = ("step", "time", "atoms", "ke", "rke", "dt_rayleigh", "dt_hertz", "cpu")


def rows_to_csv(rows: list[ThermoRow]) -> str:
    """Thermo rows as CSV text: the columns of :data:`TABLE_COLUMNS` plus the phase."""
    buf = io.StringIO()
    writer = csv.writer(buf, lineterminator="\n")
    writer.writerow(list(TABLE_COLUMNS) + ["phase"])
    for row in rows:
        writer.writerow([row.step] + [repr(row.get(c)) for c in TABLE_COLUMNS[1:]] + [row.phase])
    return buf.getvalue()


def rows_from_csv(text: str) -> list[ThermoRow]:
    """Inverse of :func:`rows_to_csv`."""
    reader = csv.DictReader(io.StringIO(text))
    rows = []
    for rec in reader:
        phase = rec.pop("phase", "")
        step = int(rec.pop("step"))
        values = {k: float(v) for k, v in rec.items()}
        values["step"] = float(step)
        rows.append(ThermoRow(step=step, values=values, phase=phase))
    return rows


#: Columns every thermo row of a finished run must hold as finite numbers.
REQUIRED_FINITE = ("time", "atoms", "ke")


def table_problem(rows: list[ThermoRow], thermo_every: int) -> str | None:
    """Why a finished run's thermo rows cannot be its own (None: they are plausible).

    The runner writes one row every ``thermo_every`` steps (and at the end of each
    ``run`` command), steps rising strictly from the first row on; a done run never
    printed nan (its health check would have stopped it). So a nan or missing number, a
    step repeated or going back, or a gap wider than ``thermo_every`` means the table was
    edited, merged wrongly or lost rows.
    """
    prev = None
    for k, row in enumerate(rows):
        bad = [c for c in REQUIRED_FINITE if not math.isfinite(row.get(c))]
        if bad:
            return f"row {k + 1} (step {row.step}) has no finite {', '.join(bad)} (nan or missing)"
        if prev is not None:
            if row.step <= prev:
                return (f"step {row.step} follows step {prev} (rows duplicated or out of "
                        "order)")
            if row.step - prev > thermo_every:
                return (f"rows missing between steps {prev} and {row.step} (the run writes "
                        f"one every {thermo_every} steps)")
        prev = row.step
    return None
