"""Shared fixtures: repository paths and the engine (real LIGGGHTS under real mpirun)."""

from __future__ import annotations

import subprocess
from pathlib import Path

import pytest

ROOT = Path(__file__).resolve().parent.parent
DRUM = ROOT / "tests" / "workflows" / "drum.yaml"
WET_POLY = ROOT / "tests" / "workflows" / "wet_poly.yaml"


@pytest.fixture(scope="session")
def engine():
    """The site's engine configuration; fails (never skips) when LIGGGHTS is missing."""
    from ligwf.engine import EngineConfig

    cfg = EngineConfig.from_site()
    cfg.liggghts_path()
    cfg.mpirun_path()
    return cfg


def run_liggghts(engine, case_dir: Path, nprocs: int = 1, timeout: float = 300) -> subprocess.CompletedProcess:
    """Run ``in.liggghts`` in ``case_dir``; stdout+stderr captured together."""
    return subprocess.run(engine.command("in.liggghts", nprocs), cwd=case_dir, text=True, errors="replace",
                          stdout=subprocess.PIPE, stderr=subprocess.STDOUT, timeout=timeout,
                          stdin=subprocess.DEVNULL)
