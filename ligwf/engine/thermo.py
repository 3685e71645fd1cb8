"""Reading LIGGGHTS screen output: thermo rows, phase markers and run timings.

The rendered input prints ``ligwf-phase <name>`` before each ``run`` and writes the thermo
``step time atoms ke c_rke f_ts[1] f_ts[2] cpu`` every ``thermo_every`` steps. This module
turns the captured stdout+stderr (the *screen*, not ``log.liggghts``: LIGGGHTS' ``ERROR on
proc N`` messages go through MPI_Abort and can be missing from the log file) into rows
a runner can watch live and a health check can judge.

Parsing is incremental (:class:`ThermoParser.feed` one line at a time) so the same code
serves the live monitor, which tails a growing file with :class:`LogTail`, and the final
read of a finished run (:func:`parse_screen`).
"""

from __future__ import annotations

import re
from dataclasses import dataclass, field
from pathlib import Path

from ligwf.study.thermo_table import ThermoRow

#: Thermo column names as LIGGGHTS prints them -> ligwf's names (SI units).
COLUMN_NAMES = {
    "Step": "step",            # time step number
    "Time": "time",            # simulated time, s
    "Atoms": "atoms",          # particle count
    "KinEng": "ke",            # translational kinetic energy, J
    "rke": "rke",              # rotational kinetic energy, J
    "ts[1]": "dt_rayleigh",    # dt as a fraction of the Rayleigh time of the smallest particle
    "ts[2]": "dt_hertz",       # dt as a fraction of the Hertz contact time
    "CPU": "cpu",              # wall seconds since the start of this run command
}

#: Prefix of the phase markers printed by the rendered input.
PHASE_MARKER = "ligwf-phase"

#: The engine's line after each run command: wall seconds, ranks, steps, atoms.
LOOP_RE = re.compile(r"^Loop time of ([0-9.eE+-]+) on (\d+) procs for (\d+) steps with (\d+) atoms")


def phase_group(marker: str) -> str:
    """Phase a marker belongs to for timing: ``fill 2`` -> ``fill``; ``settle``; ``production``."""
    return marker.split()[0] if marker else "setup"


@dataclass
class RunBlock:
    """One ``run`` command as seen on screen: its phase, steps and wall time (s)."""

    phase: str
    first_step: int | None = None
    last_step: int | None = None
    loop_seconds: float | None = None   # from "Loop time of ..."; None while running
    last_cpu: float = 0.0               # the thermo CPU column: wall s since the run began
    nprocs: int | None = None

    @property
    def wall_seconds(self) -> float:
        return self.loop_seconds if self.loop_seconds is not None else self.last_cpu

    @property
    def steps(self) -> int:
        if self.first_step is None or self.last_step is None:
            return 0
        return self.last_step - self.first_step


def _parse_number(token: str) -> float | None:
    try:
        return float(token)  # accepts nan, -nan, inf, -inf as LIGGGHTS prints them
    except ValueError:
        return None


@dataclass
class ThermoParser:
    """Incremental parser of LIGGGHTS screen output (feed it lines, read the state)."""

    rows: list[ThermoRow] = field(default_factory=list)
    runs: list[RunBlock] = field(default_factory=list)
    lines: list[str] = field(default_factory=list)
    phase: str = ""
    _header: list[str] | None = None

    def feed(self, line: str) -> ThermoRow | None:
        """Consume one line; returns the thermo row it carried, if any."""
        line = line.rstrip("\n")
        self.lines.append(line)
        stripped = line.strip()
        if not stripped:
            return None
        if stripped.startswith(PHASE_MARKER):
            self.phase = stripped[len(PHASE_MARKER):].strip()
            return None
        tokens = stripped.split()
        if tokens[0] == "Step" and len(tokens) > 1:
            self._header = [COLUMN_NAMES.get(t, t) for t in tokens]
            self.runs.append(RunBlock(phase=self.phase))
            return None
        loop = LOOP_RE.match(stripped)
        if loop:
            if self.runs:
                run = self.runs[-1]
                run.loop_seconds = float(loop.group(1))
                run.nprocs = int(loop.group(2))
            self._header = None
            return None
        if self._header is None or len(tokens) != len(self._header):
            return None
        if not re.fullmatch(r"\d+", tokens[0]):
            return None
        numbers = [_parse_number(t) for t in tokens]
        if any(n is None for n in numbers):
            return None
        values = dict(zip(self._header, numbers))  # type: ignore[arg-type]
        row = ThermoRow(step=int(tokens[0]), values=values, phase=self.phase)
        # the first row of a run repeats the last row of the previous run: keep the newer
        if self.rows and self.rows[-1].step == row.step:
            self.rows[-1] = row
        else:
            self.rows.append(row)
        run = self.runs[-1]
        if run.first_step is None:
            run.first_step = row.step
        run.last_step = row.step
        run.last_cpu = values.get("cpu", run.last_cpu)
        return row

    def feed_text(self, text: str) -> None:
        for line in text.splitlines():
            self.feed(line)

    @property
    def last_row(self) -> ThermoRow | None:
        return self.rows[-1] if self.rows else None

    def phase_walls(self) -> dict[str, float]:
        """Engine wall seconds per phase group (fill, settle, production)."""
        out: dict[str, float] = {}
        for run in self.runs:
            key = phase_group(run.phase)
            out[key] = out.get(key, 0.0) + run.wall_seconds
        return out

    def phase_steps(self) -> dict[str, int]:
        """Steps run per phase group."""
        out: dict[str, int] = {}
        for run in self.runs:
            key = phase_group(run.phase)
            out[key] = out.get(key, 0) + run.steps
        return out


def parse_screen(text: str) -> ThermoParser:
    """Parse a complete screen capture."""
    parser = ThermoParser()
    parser.feed_text(text)
    return parser


class LogTail:
    """Reads the complete lines appended to a growing file since the last call.

    The engine writes the file; ligwf only reads it, so monitoring never slows the
    engine's output (no pipe to drain).
    """

    def __init__(self, path: Path) -> None:
        self.path = Path(path)
        self._offset = 0
        self._partial = b""

    def read_lines(self) -> list[str]:
        try:
            with open(self.path, "rb") as fh:
                fh.seek(self._offset)
                data = fh.read()
        except FileNotFoundError:
            return []
        self._offset += len(data)
        data = self._partial + data
        parts = data.split(b"\n")
        self._partial = parts.pop()
        return [p.decode("utf-8", errors="replace") for p in parts]

    def flush(self) -> list[str]:
        """All remaining lines, including a last line without a newline."""
        lines = self.read_lines()
        if self._partial:
            lines.append(self._partial.decode("utf-8", errors="replace"))
            self._partial = b""
        return lines
