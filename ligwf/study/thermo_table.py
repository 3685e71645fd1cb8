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


def atom_fall(rows: list[ThermoRow], target: int | None = None
              ) -> tuple[int, float, float] | None:
    """The first drop of the atom count, as (step, count before, count then); None when it
    never falls. Atoms are only ever added, by insertion; ``target``: the particle count
    asked for (the top-up insertion wave places a few too many and deletes them one step
    later, see drum.in.j2, so with a target only a fall below min(running maximum, target)
    counts). The engine's health check (a running case) and the folder model (a finished
    case's table read back) share this rule."""
    top = -1.0
    for row in rows:
        atoms = row.get("atoms")
        if not math.isfinite(atoms):
            continue
        if atoms < top:
            return row.step, top, atoms
        top = max(top, atoms) if target is None else min(max(top, atoms), float(target))
    return None


#: Columns every thermo row of a finished run must hold as finite numbers.
REQUIRED_FINITE = ("time", "atoms", "ke")


def table_problem(rows: list[ThermoRow], thermo_every: int,
                  particle_count: int | None = None) -> str | None:
    """Why a finished run's thermo rows cannot be its own (None: they are plausible).

    The runner writes one row every ``thermo_every`` steps (and at the end of each
    ``run`` command), steps rising strictly from the first row on; a done run never
    printed nan and never lost an atom (its health check would have stopped it). So a nan
    or missing number, a step repeated or going back, a gap wider than ``thermo_every``,
    or an atom count that falls (:func:`atom_fall`, ``particle_count``: the scene's) means
    the table was edited, merged wrongly or lost rows.
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
    if (fall := atom_fall(rows, particle_count)) is not None:
        step, before, atoms = fall
        return (f"the atom count falls from {before:.0f} to {atoms:.0f} at step {step} (a "
                "finished run keeps every particle: atoms lost, or the table edited)")
    return None
