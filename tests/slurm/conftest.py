"""Fixtures of the Slurm tests: a real one-node Slurm cluster for the session.

Started only when a test asks for it (the ``slurm`` integration test); if it cannot start,
the test FAILS with the reason (installation, munge, slurmctld/slurmd logs): a missing
scheduler must not pass as a skipped test.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from local_cluster import LocalSlurm, SlurmUnavailable  # noqa: E402


@pytest.fixture(scope="session")
def slurm_cluster():
    """Install (if needed), configure and start Slurm; shut it down after the session."""
    cluster = LocalSlurm()
    try:
        cluster.start()
    except SlurmUnavailable as exc:
        cluster.stop()
        pytest.fail(f"a real Slurm is needed and could not start: {exc}", pytrace=False)
    yield cluster
    cluster.stop()
