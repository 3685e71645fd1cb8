"""The part every results script shares: a committed results folder (docs/results/NAME/)
holds a study's tables and a README written from them; the script either copies the tables
from a study folder and writes the README, or (``--check``, what the committed-results tests
run) rebuilds the README from the committed tables and fails when it differs, so that a
sentence cannot drift from its table."""

from __future__ import annotations

import argparse
import math
import shutil
import sys
from pathlib import Path
from typing import Callable, Iterable

ROOT = Path(__file__).resolve().parents[1]


def csv_text(table) -> str:
    """A committed results table as text: no index, numbers to 6 significant digits (what
    a results script writes and what its --check compares)."""
    return table.to_csv(index=False, float_format="%.6g")


def number(v, digits: int = 3) -> str:
    """A table value as the README prints it (``–`` for nan or what is not a number)."""
    try:
        v = float(v)
    except (TypeError, ValueError):
        return "–"
    return f"{v:.{digits}g}" if math.isfinite(v) else "–"


def parser(doc: str, what: str) -> argparse.ArgumentParser:
    """The arguments every results script takes: the study folder, or ``--check``."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("study", nargs="?", type=Path, help=f"the {what}'s study folder")
    ap.add_argument("--check", action="store_true",
                    help="only check that the committed README is what its tables give")
    return ap


def copy_files(source: Path, out: Path, names: Iterable[str]) -> None:
    """Copy ``names`` from ``source`` into the results folder ``out``."""
    for name in names:
        shutil.copyfile(source / name, out / name)


def write_or_check(out: Path, text: Callable[[], str], check: bool, remake: str) -> int:
    """Write ``text()`` as ``out``/README.md (and print it), or with ``check`` compare it
    with the committed one: 1 and a line naming ``remake`` (the command that remakes it)
    when they differ."""
    readme = out / "README.md"
    body = text()
    if check:
        if readme.read_text() != body:
            print(f"{readme.relative_to(ROOT)} differs from its tables: run {remake}",
                  file=sys.stderr)
            return 1
        return 0
    readme.write_text(body)
    print(body)
    return 0
