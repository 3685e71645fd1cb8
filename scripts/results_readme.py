"""The older form of a results script's shared part, kept for the scripts that still use it
(liquid_spreading_results.py, granule_screen_results.py, profile_correlation.py). A results
folder is now a type of the package: :class:`ligwf.api.results_folder.ResultsFolder` (its
tables, its README rendered from them, the tables it derives, ``check``); a new script
declares one (see demo_results.py) instead."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path
from typing import Callable

from ligwf.api.results_folder import csv_text, number

__all__ = ["ROOT", "csv_text", "number", "parser", "write_or_check"]

ROOT = Path(__file__).resolve().parents[1]


def parser(doc: str, what: str) -> argparse.ArgumentParser:
    """The arguments every results script takes: the study folder, or ``--check``."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("study", nargs="?", type=Path, help=f"the {what}'s study folder")
    ap.add_argument("--check", action="store_true",
                    help="only check that the committed README is what its tables give")
    return ap


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
