"""Shared fixtures: the engine (real LIGGGHTS under real mpirun), and the marks that keep
the fast lane (``make test-fast``: no engine, MPI or Slurm) honest. Paths and helpers live
in tests/helpers.py."""

from __future__ import annotations

import os

import pytest

#: marks a test gets from the fixtures it uses (directly or through other fixtures), so a
#: test that needs the engine or a Slurm cluster can never run in the fast lane unmarked
FIXTURE_MARKS = {"engine": ("engine",), "slurm_cluster": ("slurm",),
                 "two_node_slurm": ("slurm", "slow"), "chromium": ("browser",)}


def pytest_collection_modifyitems(config, items):
    for item in items:
        for fixture, marks in FIXTURE_MARKS.items():
            if fixture in getattr(item, "fixturenames", ()):
                for mark in marks:
                    if mark not in item.keywords:
                        item.add_marker(mark)


def in_ci() -> bool:
    """True in CI (``CI=true``, as GitHub Actions, GitLab and .ci/run's callers set it)."""
    return os.environ.get("CI", "").strip().lower() in ("true", "1", "yes")


@pytest.fixture(scope="session")
def engine():
    """The site's engine configuration. Where LIGGGHTS or mpirun is missing the test is
    skipped, saying which program was not found and how to get it; in CI (``CI=true``) it
    fails instead: there a missing engine must not pass as a skipped suite."""
    from ligwf.engine.site import EngineConfig
    from ligwf.errors import EngineNotFound

    cfg = EngineConfig.from_site()
    try:
        cfg.liggghts_path()
        cfg.mpirun_path()
    except EngineNotFound as exc:
        if in_ci():
            pytest.fail(f"CI=true and the engine is missing: {exc}", pytrace=False)
        pytest.skip(f"needs the engine: {exc} (`make install` installs it)")
    return cfg


@pytest.fixture(scope="session")
def chromium() -> str:
    """Path of Debian's headless-capable Chromium (report page tests). Skipped with the
    reason where it is missing; in CI (``CI=true``) it fails instead (``make test``
    installs it)."""
    import shutil

    path = shutil.which("chromium") or shutil.which("chromium-browser")
    if path is None:
        why = "needs Debian's chromium (`make test` installs it: apt-get install chromium)"
        if in_ci():
            pytest.fail(f"CI=true and Chromium is missing: {why}", pytrace=False)
        pytest.skip(why)
    return path
