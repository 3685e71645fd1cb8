"""A tiny real study, made once per test session through ``ligwf study`` (run + analyse +
report) and read by every test that only reads a reported study: the Python API
(tests/api/), the notebook (tests/test_notebook.py), the page in a browser
(tests/report/test_page_browser.py), permissions (tests/test_permissions.py) and the data
dictionary's check of every real table (tests/report/test_dictionary.py). A test that
changes the study works on a copy.

tests/workflows/tiny_study.yaml with the Weber rule only: two CG1 replicas (so the CG1
noise floor is measured) with their cohesionless twins (so the controls table exists) and
two CG2 replicas, no snapshots: 6 real LIGGGHTS runs of a few seconds each on one core.
"""

from __future__ import annotations

from pathlib import Path

from helpers import ROOT
from ligwf.cli.main import main

TINY = ROOT / "tests" / "workflows" / "tiny_study.yaml"
ARGS = ["--no-snapshots", "--set", "sweep.rules=[weber]", "--set", "sweep.replicas={1: 2, 2: 2}",
        "--set", "sweep.controls=[cohesionless]", "--set", "analysis.bootstrap=50",
        # each case at its own resolution: the 40 mm drum's CG2 bed is too small for 4
        # strips of 8 mm, so the study's one resolution would leave no angle at any level
        "--set", "analysis.surface_strip=0"]

_CACHE: dict[str, Path] = {}


def api_study(engine, tmp_path_factory) -> Path:
    """The reported tiny study folder (made on first use)."""
    if "study" not in _CACHE:
        out = tmp_path_factory.mktemp("apistudy") / "tiny"
        code = main(["study", str(TINY), "--out", str(out),
                     "--mesh-cache", str(out.parent / "meshes"), *ARGS])
        assert code == 0, f"ligwf study exited {code}"
        _CACHE["study"] = out
    return _CACHE["study"]
