"""Fixtures of the Slurm tests: a real one-node Slurm cluster for the session, and a real
two-node one (network namespaces, tests/slurm/two_node_cluster.py) for a module.

Started only when a test asks for one; if it cannot start, the test FAILS with the reason
(installation, namespaces, munge, slurmctld/slurmd logs): a missing scheduler must not pass
as a skipped test. Both are stopped after their last test, whether it passed or not.
"""

from __future__ import annotations

import sys
from pathlib import Path

import pytest

sys.path.insert(0, str(Path(__file__).resolve().parent))

from local_cluster import LocalSlurm, SlurmUnavailable  # noqa: E402
from two_node_cluster import TwoNodeSlurm  # noqa: E402


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


@pytest.fixture(scope="module")
def two_node_slurm():
    """Two hosts (network + UTS namespaces, a veth between them), one slurmd on each with
    one core, slurmctld on the first; processes and namespaces removed afterwards."""
    cluster = TwoNodeSlurm()
    try:
        cluster.start()
    except SlurmUnavailable as exc:
        cluster.stop()
        pytest.fail(f"a real two-node Slurm is needed and could not start: {exc}",
                    pytrace=False)
    try:
        yield cluster
    finally:
        cluster.stop()
