"""Per-rank atoms and ghosts of a finished run, as LIGGGHTS prints them after each ``run``.

After every ``run`` LIGGGHTS (LAMMPS 2013 core) prints the loop time, its breakdown
(Pair / Neigh / Comm / Outpt / Other seconds) and, over the ranks, the average, largest
and smallest count of owned atoms (``Nlocal``) and of ghost atoms (``Nghost``: copies of
neighbours' atoms inside the halo, what the exchange sends every step). These are the
measured inputs of the scaling model (``docs/results/performance/scaling_model.md``):
``Nlocal max / ave`` is the load imbalance a processor grid leaves, ``Nghost`` per rank the
halo it pays. Pure parsing, no I/O.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

from ligwf.engine.thermo import LOOP_RE

_TIME_RE = re.compile(r"^(Pair|Neigh|Comm|Outpt|Other)\s+time \(%\) = ([0-9.eE+-]+)")
_COUNT_RE = re.compile(r"^(Nlocal|Nghost):\s+([0-9.eE+-]+) ave ([0-9.eE+-]+) max "
                       r"([0-9.eE+-]+) min")


@dataclass(frozen=True)
class RankSpread:
    """One run block: its loop, the time breakdown (s) and atoms / ghosts over the ranks."""

    loop_seconds: float
    procs: int
    steps: int
    atoms: int
    seconds: dict[str, float]       # Pair, Neigh, Comm, Outpt, Other
    local_avg: float
    local_max: float
    local_min: float
    ghost_avg: float
    ghost_max: float
    ghost_min: float

    @property
    def imbalance(self) -> float:
        """Largest owned-atom count over the average (1.0: perfectly even ranks)."""
        return self.local_max / self.local_avg if self.local_avg > 0 else float("nan")

    @property
    def ghosts_per_local(self) -> float:
        """Average ghosts a rank keeps per atom it owns: the halo's relative size."""
        return self.ghost_avg / self.local_avg if self.local_avg > 0 else float("nan")


def run_spreads(log_text: str) -> list[RankSpread]:
    """Every complete run block of a LIGGGHTS log or screen, in order (a block without its
    ``Nlocal`` / ``Nghost`` lines, e.g. of a run cut short, is left out)."""
    out: list[RankSpread] = []
    cur: dict | None = None
    for raw in log_text.splitlines():
        line = raw.strip()
        if m := LOOP_RE.match(line):
            cur = {"loop_seconds": float(m.group(1)), "procs": int(m.group(2)),
                   "steps": int(m.group(3)), "atoms": int(m.group(4)), "seconds": {}}
        elif cur is not None and (m := _TIME_RE.match(line)):
            cur["seconds"][m.group(1)] = float(m.group(2))
        elif cur is not None and (m := _COUNT_RE.match(line)):
            key = "local" if m.group(1) == "Nlocal" else "ghost"
            cur[f"{key}_avg"], cur[f"{key}_max"], cur[f"{key}_min"] = (
                float(m.group(2)), float(m.group(3)), float(m.group(4)))
            if key == "ghost" and "local_avg" in cur:
                out.append(RankSpread(**cur))
                cur = None
    return out


def last_run_spread(log_text: str) -> RankSpread:
    """The last complete run block (the production run of a ligwf case); ValueError when
    the log has none."""
    blocks = run_spreads(log_text)
    if not blocks:
        raise ValueError("no complete 'Loop time' block with Nlocal/Nghost in the log")
    return blocks[-1]
