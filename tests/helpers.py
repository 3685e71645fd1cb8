"""Shared test helpers: repository paths and running the real engine in a case folder.

(Kept out of conftest.py: tests/slurm has its own conftest, and ``from conftest import``
would pick whichever pytest imported last.)
"""

from __future__ import annotations

import subprocess
from pathlib import Path

ROOT = Path(__file__).resolve().parent.parent
DRUM = ROOT / "tests" / "workflows" / "drum.yaml"
WET_POLY = ROOT / "tests" / "workflows" / "wet_poly.yaml"


def run_liggghts(engine, case_dir: Path, nprocs: int = 1, timeout: float = 300) -> subprocess.CompletedProcess:
    """Run ``in.liggghts`` in ``case_dir``; stdout+stderr captured together."""
    return subprocess.run(engine.command("in.liggghts", nprocs), cwd=case_dir, text=True,
                          errors="replace", stdout=subprocess.PIPE, stderr=subprocess.STDOUT,
                          timeout=timeout, stdin=subprocess.DEVNULL)
