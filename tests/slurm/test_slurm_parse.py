"""Parsers of Slurm text, against output captured from a real Slurm 22.05 (tests/data/slurm)."""

from __future__ import annotations

from pathlib import Path

import pytest

from ligwf.errors import SubmitError
from ligwf.slurm.parse import (QueueEntry, expand_task_ids, is_unknown_job, parse_records,
                               parse_sbatch_parsable, parse_squeue, task_records)

DATA = Path(__file__).resolve().parents[1] / "data" / "slurm"


def test_sbatch_parsable():
    assert parse_sbatch_parsable("1\n") == "1"
    assert parse_sbatch_parsable("4711;cluster-a\n") == "4711"
    with pytest.raises(SubmitError):
        parse_sbatch_parsable("")
    with pytest.raises(SubmitError):
        parse_sbatch_parsable("sbatch: error: invalid partition specified: nope\n")


def test_squeue_running_array_with_pending_tail_and_dependency():
    entries = parse_squeue((DATA / "squeue_array_running.txt").read_text())
    assert QueueEntry("1_2", "1", 2, "PENDING", "JobArrayTaskLimit") in entries
    assert QueueEntry("1_0", "1", 0, "RUNNING", "None") in entries
    assert QueueEntry("2", "2", None, "PENDING", "Dependency") in entries
    assert sorted(e.array_task_id for e in entries if e.array_job_id == "1") == [0, 1, 2, 3]


def test_squeue_after_cancel_drops_the_cancelled_task():
    entries = parse_squeue((DATA / "squeue_after_scancel.txt").read_text())
    tasks = {e.array_task_id: e.state for e in entries if e.array_job_id == "1"}
    assert tasks == {0: "RUNNING", 2: "RUNNING", 3: "PENDING"}


def test_squeue_collapsed_pending_range_is_expanded():
    entries = parse_squeue("7_[2-3%2]|7|2-3%2|PENDING|JobArrayTaskLimit\n")
    assert [(e.job_id, e.array_task_id) for e in entries] == [("7_2", 2), ("7_3", 3)]


def test_squeue_rejects_foreign_format():
    with pytest.raises(SubmitError):
        parse_squeue("JOBID PARTITION NAME USER ST TIME NODES\n")


@pytest.mark.parametrize("text,expected", [
    ("7", [7]), ("0-3%2", [0, 1, 2, 3]), ("[1,4-5]", [1, 4, 5]), ("0-6:3", [0, 3, 6]),
])
def test_expand_task_ids(text, expected):
    assert expand_task_ids(text) == expected


def test_scontrol_records_keep_odd_keys_and_values():
    rec = parse_records((DATA / "scontrol_array_running.txt").read_text())[0]
    assert rec["JobId"] == "1" and rec["ArrayTaskId"] == "2-3%2"
    assert rec["AllocNode:Sid"] == "localhost:4440"
    assert rec["CPUs/Task"] == "1"
    assert rec["TRES"] == "cpu=1,mem=24105M,node=1,billing=1"
    assert rec["Command"] == "/tmp/cap/arr.sh"


def test_scontrol_running_array_task_records():
    recs = task_records((DATA / "scontrol_array_running.txt").read_text())
    states = {r.array_task_id: r.state for r in recs}
    assert states == {0: "RUNNING", 1: "RUNNING", 2: "PENDING", 3: "PENDING"}
    assert not any(r.finished for r in recs)


def test_scontrol_finished_array_with_cancelled_task():
    recs = task_records((DATA / "scontrol_array_finished.txt").read_text())
    by_task = {r.array_task_id: r for r in recs}
    assert set(by_task) == {0, 1, 2, 3}
    assert by_task[1].state == "CANCELLED" and by_task[1].exit_code == "143:0"
    assert all(by_task[i].state == "COMPLETED" for i in (0, 2, 3))
    assert all(r.finished for r in recs)


def test_jobcomp_file_records():
    recs = task_records((DATA / "jobcomp_array_cancel.txt").read_text())
    arrays = {r.array_task_id: r.state for r in recs if r.array_job_id == "1"}
    assert arrays == {0: "COMPLETED", 1: "CANCELLED", 2: "COMPLETED", 3: "COMPLETED"}
    plain = [r for r in recs if r.array_job_id is None]
    assert [(r.job_id, r.state) for r in plain] == [("2", "COMPLETED")]


def test_command_with_spaces_survives():
    rec = parse_records("JobId=9 JobState=RUNNING Command=/my runs/x.sh WorkDir=/my runs")[0]
    assert rec["Command"] == "/my runs/x.sh" and rec["WorkDir"] == "/my runs"


def test_unknown_job_text():
    assert is_unknown_job("slurm_load_jobs error: Invalid job id specified\n")
    assert not is_unknown_job("JobId=1 JobState=RUNNING")
