"""The engine a user names is the one that runs (issue 32): one setting, the library
derived from the executable, refused before anything is written when it cannot be loaded."""

from __future__ import annotations

import json
import os
import shutil
import subprocess
import sys
from pathlib import Path

import pytest

from ligwf.engine.site import EngineConfig, linked_library
from ligwf.errors import EngineNotFound

from helpers import ROOT  # noqa: E402

WORKFLOW = ROOT / "tests" / "workflows" / "runner_tiny.yaml"


def test_a_wrapper_script_is_refused_with_its_name(tmp_path):
    script = tmp_path / "liggghts"
    script.write_text('#!/bin/sh\nexec liggghts "$@"\n')
    script.chmod(0o755)
    with pytest.raises(EngineNotFound, match="not a program file.*wrapper script"):
        linked_library(str(script))


def test_a_program_without_the_library_is_refused():
    with pytest.raises(EngineNotFound, match="does not link to a libliggghts"):
        linked_library(shutil.which("true") or "/bin/true")


def _library_copy(folder: Path, engine: EngineConfig, whole: bool = True) -> Path:
    """A copy of the engine's library where the loader finds it first (LD_LIBRARY_PATH):
    what a user with their own build has."""
    real = Path(linked_library(engine.liggghts_path()))
    folder.mkdir()
    data = real.read_bytes()
    (folder / "libliggghts.so.3").write_bytes(data if whole else data[:100_000])
    return folder / "libliggghts.so.3"


def test_identify_finds_the_library_the_executable_loads(engine, tmp_path, monkeypatch):
    copy = _library_copy(tmp_path / "lib", engine)
    monkeypatch.setenv("LD_LIBRARY_PATH", str(copy.parent))
    (tmp_path / "cwd").mkdir()
    monkeypatch.chdir(tmp_path / "cwd")
    found = engine.identify()
    assert found.library == str(copy)
    assert list((tmp_path / "cwd").iterdir()) == []      # `liggghts -h` alone leaves a log
    assert found.version.startswith("LIGGGHTS (Version LIGGGHTS-PUBLIC")


def test_a_damaged_library_is_refused_before_anything_is_written(engine, tmp_path):
    copy = _library_copy(tmp_path / "lib", engine, whole=False)
    out = tmp_path / "study"
    r = subprocess.run([sys.executable, "-m", "ligwf.cli.main", "run", str(WORKFLOW), "--out",
                        str(out)], capture_output=True, text=True, timeout=120,
                       env={**os.environ, "LD_LIBRARY_PATH": str(copy.parent)})
    assert r.returncode == 2, r.stdout + r.stderr
    assert "EngineNotFound" in r.stderr and "cannot be loaded" in r.stderr
    assert "Traceback" not in r.stderr and not out.exists()


@pytest.mark.mpi
@pytest.mark.slow
def test_the_ensemble_path_loads_the_named_engines_library(engine, tmp_path):
    """Two cases run side by side in one ensemble (ctypes); they must load the copy the
    executable links to, say so, and record it (the worker refuses a different mapping)."""
    copy = _library_copy(tmp_path / "lib", engine)
    out = tmp_path / "study"
    r = subprocess.run([sys.executable, "-m", "ligwf.cli.main", "run", str(WORKFLOW), "--out",
                        str(out)], capture_output=True, text=True, timeout=600,
                       env={**os.environ, "LD_LIBRARY_PATH": str(copy.parent)})
    assert r.returncode == 0, r.stdout + r.stderr
    assert f"library {copy}" in " ".join(r.stdout.split())
    for case in sorted(p for p in out.iterdir() if (p / "manifest.json").exists()):
        m = json.loads((case / "manifest.json").read_text())
        assert m["launcher"] == "ensemble" and m["status"] == "done", m["reason"]
        assert m["liggghts_library"] == str(copy)
        assert m["liggghts_version"].startswith("LIGGGHTS Version LIGGGHTS-PUBLIC")


@pytest.mark.slow
def test_a_launcher_that_fails_before_the_engine_is_named(engine, tmp_path):
    """LIGWF_MPIRUN=/bin/false used to read "engine exit code 1": an engine that never ran."""
    out = tmp_path / "study"
    r = subprocess.run([sys.executable, "-m", "ligwf.cli.main", "run", str(WORKFLOW), "--out",
                        str(out), "--np", "1", "--set", "sweep.rules=[bond]"],
                       capture_output=True, text=True, timeout=300,
                       env={**os.environ, "LIGWF_MPIRUN": shutil.which("false") or "/bin/false"})
    assert r.returncode == 1, r.stdout + r.stderr
    m = json.loads(next(out.glob("*/manifest.json")).read_text())
    assert m["status"] == "failed"
    assert m["reason"].startswith("launcher ") and "before the engine started" in m["reason"]
