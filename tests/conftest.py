"""Shared fixtures: the engine (real LIGGGHTS under real mpirun). Paths and helpers live in
tests/helpers.py."""

from __future__ import annotations

import pytest


@pytest.fixture(scope="session")
def engine():
    """The site's engine configuration; fails (never skips) when LIGGGHTS is missing."""
    from ligwf.engine.site import EngineConfig

    cfg = EngineConfig.from_site()
    cfg.liggghts_path()
    cfg.mpirun_path()
    return cfg
