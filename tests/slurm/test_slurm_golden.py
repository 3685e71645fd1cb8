"""Generated batch scripts against their golden references (tests/golden/slurm/)."""

from __future__ import annotations

import importlib.util
import shutil
import subprocess
from pathlib import Path

import pytest

GOLDEN = Path(__file__).resolve().parents[1] / "golden" / "slurm"


def _cases():
    spec = importlib.util.spec_from_file_location("slurm_golden", GOLDEN / "regenerate.py")
    module = importlib.util.module_from_spec(spec)
    spec.loader.exec_module(module)
    return module.CASES


CASES = _cases()


@pytest.mark.parametrize("name", sorted(CASES))
def test_script_matches_golden(name):
    expected = (GOLDEN / name).read_text()
    assert CASES[name]() == expected, (
        f"{name} changed; if deliberate, run tests/golden/slurm/regenerate.py and review the diff")


@pytest.mark.parametrize("name", sorted(CASES))
def test_script_is_valid_bash(name):
    assert shutil.which("bash")
    out = subprocess.run(["bash", "-n", str(GOLDEN / name)], capture_output=True, text=True)
    assert out.returncode == 0, out.stderr


def test_every_golden_file_has_a_case():
    on_disk = {p.name for p in GOLDEN.glob("*.sh")}
    assert on_disk == set(CASES)


def test_array_script_essentials():
    text = (GOLDEN / "array_minimal.sh").read_text()
    assert text.startswith("#!/bin/bash\n")
    assert "#SBATCH --array=0-3\n" in text
    assert "_%A_%a.out" in text
    assert 'run-case /scratch/alice/drum-study --index "$SLURM_ARRAY_TASK_ID"' in text
    # directives must come before the first command or sbatch ignores them
    lines = text.splitlines()
    first_cmd = next(i for i, ln in enumerate(lines[1:], 1) if not ln.startswith("#"))
    assert all(not ln.startswith("#SBATCH") for ln in lines[first_cmd:])
