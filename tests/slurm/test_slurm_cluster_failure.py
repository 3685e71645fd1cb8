"""The test cluster reports why it cannot start (the fixture turns that into a failure).

Runs before the integration test (file order) and leaves no daemon of its own behind.
"""

from __future__ import annotations

import shutil

import pytest

from local_cluster import LocalSlurm, SlurmUnavailable

pytestmark = [pytest.mark.slurm]


def test_bad_configuration_is_reported_with_slurms_reason(tmp_path):
    cluster = LocalSlurm(root=tmp_path / "state", log_dir=tmp_path / "log",
                         extra_conf=("NoSuchSlurmOption=1",))
    try:
        with pytest.raises(SlurmUnavailable) as info:
            cluster.start(timeout=20)
    finally:
        cluster.stop()
    message = str(info.value)
    assert "slurmctld" in message and "NoSuchSlurmOption" in message, message
    assert shutil.which("slurmctld"), "the fixture should have installed Slurm"
    assert not cluster.started
