"""A tiny real study, made once per test session through ``ligwf study`` (run + analyse +
report) and read by every test that only reads a reported study: the Python API
(tests/api/), the notebook (tests/test_notebook.py), the page in a browser
(tests/report/test_page_browser.py), permissions (tests/test_permissions.py), the data
dictionary's check of every real table (tests/report/test_dictionary.py) and the marks and
verdict of a fresh study against their intervals (tests/report/test_marks_study.py, which
also reads what ``ligwf study`` printed). A test that changes the study works on a copy.

tests/workflows/tiny_study.yaml under both rules: two CG1 replicas (so the CG1 noise floor
is measured) with their cohesionless twins (so the controls table exists) and two CG2
replicas per rule, no snapshots: 8 real LIGGGHTS runs of a few seconds each on one core.
Run as its own process, as a user runs it, so its standard output is kept
(:func:`api_study_stdout`).
"""

from __future__ import annotations

import subprocess
import sys
from pathlib import Path

from helpers import ROOT

TINY = ROOT / "tests" / "workflows" / "tiny_study.yaml"
ARGS = ["--no-snapshots", "--set", "sweep.rules=[weber,bond]",
        "--set", "sweep.replicas={1: 2, 2: 2}",
        "--set", "sweep.controls=[cohesionless]", "--set", "analysis.bootstrap=50",
        # each case at its own resolution: the 40 mm drum's CG2 bed is too small for 4
        # strips of 8 mm, so the study's one resolution would leave no angle at any level
        "--set", "analysis.surface_strip=0"]

_CACHE: dict[str, Path] = {}
#: what ``ligwf study`` printed, kept beside (not inside) the study folder
STDOUT = "study_stdout.txt"


def api_study(engine, tmp_path_factory) -> Path:
    """The reported tiny study folder (made on first use)."""
    if "study" not in _CACHE:
        out = tmp_path_factory.mktemp("apistudy") / "tiny"
        r = subprocess.run([sys.executable, "-m", "ligwf.cli.main", "study", str(TINY),
                            "--out", str(out), "--mesh-cache", str(out.parent / "meshes"),
                            *ARGS], capture_output=True, text=True, timeout=3000)
        assert r.returncode == 0, f"ligwf study exited {r.returncode}: {r.stderr[-3000:]}"
        assert "Traceback" not in r.stderr, r.stderr[-3000:]
        (out.parent / STDOUT).write_text(r.stdout)
        _CACHE["study"] = out
    return _CACHE["study"]


def api_study_stdout(engine, tmp_path_factory) -> str:
    """What ``ligwf study`` printed while it made :func:`api_study`'s folder."""
    return (api_study(engine, tmp_path_factory).parent / STDOUT).read_text()
