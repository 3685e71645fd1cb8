"""The fast lane's guarantees (tests/conftest.py): a test using the engine or Slurm
fixtures is marked so even when its author forgot, and the engine fixture skips with the
reason where LIGGGHTS or mpirun is missing, except in CI (``CI=true``), where it fails."""

from __future__ import annotations

import os
import subprocess
import sys
from pathlib import Path

import pytest

from helpers import ROOT

_CONFTEST = f"""
import importlib.util
spec = importlib.util.spec_from_file_location("ligwf_tests_conftest",
                                              {str(ROOT / "tests" / "conftest.py")!r})
shared = importlib.util.module_from_spec(spec)
spec.loader.exec_module(shared)
engine = shared.engine
pytest_collection_modifyitems = shared.pytest_collection_modifyitems


def pytest_collection_finish(session):
    for item in session.items:
        print("MARKS", item.name, sorted(m.name for m in item.iter_markers()))
"""

_TESTS = """
import pytest

def test_needs_the_engine(engine):
    assert engine.liggghts

@pytest.fixture
def slurm_cluster():
    return "a cluster"

def test_needs_slurm(slurm_cluster):
    pass

def test_plain():
    pass
"""


def _pytest(folder: Path, *args: str, **env: str) -> subprocess.CompletedProcess:
    full = {k: v for k, v in os.environ.items() if k != "CI"}
    full.update(env)
    return subprocess.run([sys.executable, "-m", "pytest", "-q", "-rs", "-p", "no:cacheprovider",
                           "--rootdir", str(folder), *args, str(folder)], cwd=folder,
                          env=full, text=True, capture_output=True, timeout=300)


@pytest.fixture
def folder(tmp_path):
    (tmp_path / "conftest.py").write_text(_CONFTEST)
    (tmp_path / "test_sample.py").write_text(_TESTS)
    return tmp_path


def test_fixtures_mark_their_tests_and_a_missing_mpirun_skips_with_the_reason(folder):
    proc = _pytest(folder, "-s", LIGWF_MPIRUN="/nonexistent/mpirun")
    assert "MARKS test_needs_the_engine ['engine']" in proc.stdout, proc.stdout
    assert "MARKS test_needs_slurm ['slurm']" in proc.stdout
    assert "MARKS test_plain []" in proc.stdout
    assert proc.returncode == 0 and "2 passed, 1 skipped" in proc.stdout, proc.stdout
    assert "needs the engine" in proc.stdout and "/nonexistent/mpirun" in proc.stdout


def test_missing_engine_fails_in_ci(folder):
    proc = _pytest(folder, "-k", "engine", LIGWF_LIGGGHTS="/nonexistent/liggghts", CI="true")
    assert proc.returncode != 0 and "1 error" in proc.stdout, proc.stdout
    assert "CI=true and the engine is missing" in proc.stdout
    assert "/nonexistent/liggghts" in proc.stdout


@pytest.mark.slow
def test_the_list_of_slow_tests_is_current():
    """docs/slow_tests.md says what each test outside the fast lane is for; it is pytest's
    own collection of them (scripts/slow_tests.py --check collects again, ~20 s: slow)."""
    r = subprocess.run([sys.executable, str(ROOT / "scripts" / "slow_tests.py"), "--check"],
                       capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stderr
