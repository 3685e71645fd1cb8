"""Partial outputs of an analysis split over array tasks, and their merge.

A big study's analysis can run as N independent processes (a Slurm array, ``ligwf
analyse STUDY --slurm N``): task K computes exactly the share MPI rank K of N would
(:meth:`ligwf.analysis.runner.AnalysisShares.share`: a contiguous run of the (case, frame)
tasks, and the flow of the cases whose middle frame it holds) and writes it as one file,
atomically (:func:`write_part`), into ``OUT/.parts-<token>/``; its labelled ``.vtu``
frames go into the analysis' staging folder of the same token. The merge (``--merge N``)
reads the N parts (:func:`read_parts`) and writes the outputs as a local run does, so the
tables are the same bytes. A part is accepted only when it was computed for the same
plan (the fingerprint of its cases, frames, dump records, settings and options); a task
that failed, was killed or has not finished leaves no part, and the merge names it with
the command that re-runs it (:class:`AnalysisIncomplete`), keeping the parts and the
staged frames so only the missing tasks run again.

Parts are pickles: transient files written and read by the same ligwf version of the same
study, never an output (the merge removes them once the outputs are committed).
"""

from __future__ import annotations

import pickle
import re
import shutil
from dataclasses import dataclass, field
from pathlib import Path

from ligwf import __version__
from ligwf.analysis.granules.case import FrameResult
from ligwf.errors import ConfigError, LigwfError
from ligwf.fsio import atomic_write_bytes
from ligwf.study import layout

#: the largest number of array tasks (Slurm's default MaxArraySize is 1001)
MAX_TASKS = 10_000
_TOKEN = re.compile(r"[A-Za-z0-9]{1,32}")


class AnalysisIncomplete(LigwfError):
    """Some array tasks of a split analysis left no (valid) partial output."""


@dataclass
class Share:
    """What one rank or array task computed: frame results and flows of its cases."""

    results: list[FrameResult] = field(default_factory=list)
    flows: dict = field(default_factory=dict)        # case_id -> CaseFlow
    notes: dict = field(default_factory=dict)        # case_id -> skipped-frame notes


def parse_part(text: str) -> tuple[int, int]:
    """``K/N`` -> (K, N); ConfigError naming the value and the allowed range."""
    m = re.fullmatch(r"\s*(\d+)\s*/\s*(\d+)\s*", str(text))
    if m is None:
        raise ConfigError(f"--part {text!r}: expected K/N, task K of N tasks "
                          f"(0 <= K < N <= {MAX_TASKS})")
    index, count = int(m.group(1)), int(m.group(2))
    check_count(count, "--part N")
    if not 0 <= index < count:
        raise ConfigError(f"--part {text}: task index {index} outside the allowed range "
                          f"[0, {count - 1}]")
    return index, count


def check_count(count: int, name: str = "--slurm") -> int:
    """The number of tasks, or ConfigError naming it and the allowed range."""
    if isinstance(count, bool) or not isinstance(count, int) or not 1 <= count <= MAX_TASKS:
        raise ConfigError(f"{name} = {count!r}: number of analysis tasks, allowed range "
                          f"[1, {MAX_TASKS}]")
    return count


def check_token(token: str) -> str:
    """A staging token (letters and digits, 1-32), or ConfigError."""
    if not isinstance(token, str) or _TOKEN.fullmatch(token) is None:
        raise ConfigError(f"--token {token!r}: 1-32 letters or digits (the token "
                          "`ligwf analyse --slurm` printed)")
    return token


def parts_dir(out_dir: Path, token: str) -> Path:
    return Path(out_dir) / layout.analysis_parts_dir(check_token(token))


def write_part(out_dir: Path, token: str, index: int, count: int, fingerprint: str,
               share: Share) -> Path:
    """Write task ``index``'s share atomically (a reader finds all of it or nothing)."""
    path = parts_dir(out_dir, token) / layout.analysis_part(index, count)
    payload = {"ligwf_version": __version__, "fingerprint": fingerprint, "index": index,
               "count": count, "share": share}
    atomic_write_bytes(path, pickle.dumps(payload, protocol=pickle.HIGHEST_PROTOCOL))
    return path


def read_parts(out_dir: Path, token: str, count: int, fingerprint: str,
               rerun: str) -> list[Share]:
    """The ``count`` shares in task order; AnalysisIncomplete naming every missing or
    foreign part and the command that re-runs them (``rerun``: with ``{index}``)."""
    folder = parts_dir(out_dir, token)
    shares, missing, foreign = [], [], []
    for index in range(count):
        path = folder / layout.analysis_part(index, count)
        try:
            payload = pickle.loads(path.read_bytes())
        except FileNotFoundError:
            missing.append(index)
            continue
        except Exception as exc:        # noqa: BLE001 - a damaged part is a missing one
            foreign.append(f"{index} (unreadable: {type(exc).__name__})")
            continue
        if not isinstance(payload, dict) or payload.get("fingerprint") != fingerprint \
                or payload.get("index") != index or payload.get("count") != count:
            foreign.append(f"{index} (computed for another plan: the cases, frames, dump "
                           "records or settings changed since)")
            continue
        shares.append(payload["share"])
    if missing or foreign:
        what = []
        if missing:
            what.append(f"task(s) {_ranges(missing)} of {count} left no partial output "
                        "(failed, killed or not finished: see their logs)")
        if foreign:
            what.append("part(s) " + ", ".join(foreign))
        raise AnalysisIncomplete(
            f"{folder}: " + "; ".join(what) + "; re-run each with `"
            + rerun.format(index=(missing or [int(foreign[0].split()[0])])[0])
            + "` (one per task), then merge again; the outputs in place are unchanged")
    return shares


def drop_parts(out_dir: Path, token: str) -> None:
    """Remove the partial outputs (after the merged outputs are committed)."""
    shutil.rmtree(parts_dir(out_dir, token), ignore_errors=True)


def _ranges(values: list[int]) -> str:
    """[0, 1, 2, 5] -> '0-2, 5'."""
    out, start = [], None
    for k, v in enumerate(values):
        if start is None:
            start = v
        if k + 1 == len(values) or values[k + 1] != v + 1:
            out.append(str(start) if start == v else f"{start}-{v}")
            start = None
    return ", ".join(out)
