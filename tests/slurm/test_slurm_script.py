"""Pure builders of sbatch/squeue/scontrol argv and --array specs."""

from __future__ import annotations

import pytest

from ligwf.errors import ConfigError
from ligwf.slurm.script import (SQUEUE_FORMAT, array_spec, sbatch_command, scancel_command,
                                scontrol_command, squeue_command)


@pytest.mark.parametrize("indices,k,expected", [
    ([0, 1, 2, 3], None, "0-3"),
    ([0, 1, 2, 3], 2, "0-3%2"),
    ([3, 1, 2, 0, 2], None, "0-3"),
    ([5], 1, "5%1"),
    ([1, 3, 4, 5, 9], None, "1,3-5,9"),
    ([0, 2, 4], 3, "0,2,4%3"),
])
def test_array_spec(indices, k, expected):
    assert array_spec(indices, k) == expected


def test_array_spec_round_trips_through_slurm_expansion():
    from ligwf.slurm.parse import expand_task_ids
    indices = [0, 1, 2, 7, 8, 11, 20, 21, 22, 23]
    assert expand_task_ids(array_spec(indices, 4)) == indices


@pytest.mark.parametrize("indices,k", [([], None), ([-1, 0], None), ([0], 0)])
def test_array_spec_rejects(indices, k):
    with pytest.raises(ConfigError):
        array_spec(indices, k)


def test_sbatch_command():
    assert sbatch_command("/s/slurm/array-1.sh") == ["sbatch", "--parsable", "/s/slurm/array-1.sh"]
    assert sbatch_command("/s/a.sh", after_any="42") == [
        "sbatch", "--parsable", "--dependency=afterany:42", "/s/a.sh"]
    with pytest.raises(ConfigError):
        sbatch_command("/s/a.sh", after_any="42;rm -rf /")


def test_sbatch_command_waits_for_several_arrays():
    # a planned study has one array per rank count; its analysis job waits for all
    assert sbatch_command("/s/a.sh", after_any=["42", "43"]) == [
        "sbatch", "--parsable", "--dependency=afterany:42:43", "/s/a.sh"]
    for bad in ([], ["42", "43;rm -rf /"], ["42:43"]):
        with pytest.raises(ConfigError):
            sbatch_command("/s/a.sh", after_any=bad)


def test_queue_commands():
    assert squeue_command("alice") == ["squeue", "-h", "-r", "-u", "alice", "-o", SQUEUE_FORMAT]
    assert scontrol_command("12") == ["scontrol", "-o", "show", "job", "12"]
    assert scancel_command("12", 3) == ["scancel", "12_3"]
    assert scancel_command("12") == ["scancel", "12"]
