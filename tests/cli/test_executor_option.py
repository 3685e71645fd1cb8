"""``--executor``: ``ligwf study --executor slurm`` is ``ligwf slurm submit`` and ``ligwf
analyse --executor slurm --tasks N`` is ``ligwf analyse --slurm N`` (the same code, so the
same scripts); the options of one executor are refused with another, in one line, before
anything is written. (The real submissions: tests/slurm.)"""

from __future__ import annotations

import re
import subprocess
from dataclasses import dataclass

import pytest

from ligwf.cli.executors import (CANCEL, FOLLOW_UP, RESUBMIT, SHOW_STATUS, STUDY_OPTIONS,
                                 SUBMIT_ANALYSIS, SUBMIT_STUDY)
from ligwf.cli.main import main
from ligwf.executors import EXECUTORS, LOCAL
from ligwf.slurm.jobs import append_record

from helpers import ROOT

TINY = ROOT / "tests" / "slurm" / "tiny_drum.yaml"


@dataclass(frozen=True)
class Ran:
    returncode: int
    stdout: str
    stderr: str


@pytest.fixture
def ligwf(tmp_path, monkeypatch, capsys):
    """``ligwf ARGS`` in this process, on no site file and a mesh cache of the test's own."""
    monkeypatch.setenv("LIGWF_MESH_CACHE", str(tmp_path / "meshes"))
    monkeypatch.setenv("LIGWF_SITE", str(tmp_path / "none.yaml"))
    monkeypatch.setenv("LIGWF_SLURM_MODULES", "openmpi/4.1")

    def run(*args) -> Ran:
        capsys.readouterr()
        code = main([str(a) for a in args])
        out, err = capsys.readouterr()
        return Ran(code, out, err)
    return run


@pytest.fixture
def study(tmp_path, ligwf):
    """The tiny drum rendered (four cases, nothing run)."""
    folder = tmp_path / "study"
    assert ligwf("render", TINY, "--out", folder).returncode == 0
    return folder


def test_every_scheduler_in_the_registry_has_its_command_line_face():
    schedulers = set(EXECUTORS) - {LOCAL}
    for face in (SUBMIT_STUDY, SUBMIT_ANALYSIS, SHOW_STATUS, CANCEL, RESUBMIT, FOLLOW_UP):
        assert set(face) == schedulers
    assert {owner for owner, _, _ in STUDY_OPTIONS.values()} == set(EXECUTORS)


@pytest.mark.parametrize("extra", [(), ("--until-decided", "--max-looks", "2")])
def test_study_on_slurm_is_slurm_submit(tmp_path, ligwf, extra):
    out = tmp_path / "study"
    site = ("--partition", "debug", "--time", "00:05:00", "--max-concurrent", "2")
    old = ligwf("slurm", "submit", TINY, "--out", out, "--dry-run", *site, *extra)
    new = ligwf("study", TINY, "--out", out, "--executor", "slurm", "--dry-run",
                 *site, *extra)
    assert old.returncode == new.returncode == 0, old.stderr + new.stderr
    assert new.stdout == old.stdout and new.stderr == old.stderr
    assert "#SBATCH --array=0-3%2" in new.stdout and "#SBATCH --partition=debug" in new.stdout
    assert ("slurm next-round" in new.stdout) == bool(extra)
    assert not out.exists()


def test_analyse_on_slurm_is_analyse_slurm(ligwf, study):
    old = ligwf("analyse", study, "--slurm", "3", "--dry-run")
    new = ligwf("analyse", study, "--executor", "slurm", "--tasks", "3",
                 "--dry-run")
    assert old.returncode == new.returncode == 0, old.stderr + new.stderr
    tokens = [re.search(r"--token (\w+)", r.stdout).group(1) for r in (old, new)]
    assert tokens[0] != tokens[1]           # each split draws its own staging token
    assert new.stdout.replace(tokens[1], "TOKEN") == old.stdout.replace(tokens[0], "TOKEN")
    assert new.stdout.count("--part") == 1 and "--merge 3 --token" in new.stdout
    assert not (study / "slurm").exists()


@pytest.mark.parametrize("args, message", [
    (("--executor", "pbs"), "ConfigError: --executor = 'pbs': no such executor (allowed: "
                            "local, slurm)"),
    (("--executor", "slurm", "--np", "2"), "--np: an option of --executor local, not of "
                                           "--executor slurm"),
    (("--executor", "slurm", "--extend-production", "1"), "--extend-production: an option "
                                                          "of --executor local"),
    (("--partition", "debug"), "--partition: an option of --executor slurm, not of "
                               "--executor local"),
    (("--dry-run",), "--dry-run: an option of --executor slurm"),
])
def test_another_executors_option_is_one_line_and_writes_nothing(tmp_path, ligwf, args,
                                                                message):
    out = tmp_path / "study"
    res = ligwf("study", TINY, "--out", out, *args)
    assert res.returncode == 2 and message in res.stderr
    assert len(res.stderr.strip().splitlines()) == 1
    assert not out.exists() and not (tmp_path / "meshes").exists()


@pytest.mark.parametrize("args, message", [
    (("--executor", "pbs"), "--executor = 'pbs': no such executor"),
    (("--tasks", "0"), "--tasks = 0: number of analysis tasks, allowed range [1, "),
    (("--tasks", "2", "--out", "elsewhere"), "--executor local --tasks 2 runs the study's own "
                                             "analysis"),
    (("--tasks", "2", "--dry-run"), "--dry-run: the local executor runs the shares now"),
    (("--tasks", "2", "--part", "0/2", "--token", "abc"), "--part: one share or the merge"),
    (("--executor", "slurm", "--token", "abc"), "--token: --tasks makes its own token"),
])
def test_analyse_refuses_what_its_executor_cannot_do(ligwf, study, args, message):
    res = ligwf("analyse", study, *args)
    assert res.returncode == 2 and message in res.stderr, res.stderr
    assert not (study / "analysis").exists()


class Queue:
    """Slurm's commands: task 2 of array 1 running; scancel recorded."""

    def __init__(self) -> None:
        self.cancelled: list[list[str]] = []

    def __call__(self, argv):
        if argv[0] == "squeue":
            return subprocess.CompletedProcess(argv, 0, stdout="1_2|1|2|RUNNING|None\n",
                                               stderr="")
        if argv[0] == "scancel":
            self.cancelled.append(list(argv))
            return subprocess.CompletedProcess(argv, 0, stdout="", stderr="")
        return subprocess.CompletedProcess(argv, 1, stdout="", stderr=(
            "slurm_load_jobs error: Invalid job id specified"))


def test_status_and_cancel_on_slurm_are_the_slurm_commands(ligwf, study, monkeypatch):
    import ligwf.cli.slurm as cli_slurm
    import ligwf.slurm.scheduler as slurm_scheduler
    from ligwf.slurm.jobs import study_status
    from ligwf.slurm.scheduler import SlurmScheduler

    append_record(study, {"kind": "array", "job_id": "1", "indices": [0, 1, 2, 3]})
    queue = Queue()
    monkeypatch.setattr(cli_slurm, "study_status", lambda path, tolerant: study_status(
        path, queue, tolerant=tolerant))
    monkeypatch.setattr(slurm_scheduler, "SlurmScheduler",
                        lambda site: SlurmScheduler(site, queue))
    old, new = ligwf("slurm", "status", study), ligwf("status", study, "--executor", "slurm")
    assert old == new and old.returncode == 0
    assert "1_2" in new.stdout and "RUNNING" in new.stdout
    old, new = ligwf("slurm", "cancel", study), ligwf("cancel", study, "--executor", "slurm")
    assert old == new and "cancelled job(s) 1" in new.stdout
    assert queue.cancelled == [["scancel", "1"], ["scancel", "1"]]
    local = ligwf("cancel", study)                   # this machine: no runner holds a case
    assert local.returncode == 0 and "no live ligwf runner" in local.stdout


def test_resubmit_and_next_round_on_slurm_are_the_slurm_commands(ligwf, study, monkeypatch):
    """``ligwf resubmit|next-round STUDY --executor slurm`` are ``ligwf slurm
    resubmit|next-round``: the same scripts for the same cases; on this machine both are
    refused in one line that names the command doing it here."""
    import ligwf.slurm.scheduler as slurm_scheduler
    from ligwf.slurm.scheduler import SlurmScheduler

    append_record(study, {"kind": "array", "job_id": "1", "indices": [0, 1, 2, 3]})
    queue = Queue()
    monkeypatch.setattr(slurm_scheduler, "SlurmScheduler",
                        lambda site: SlurmScheduler(site, queue))
    site = ("--partition", "debug", "--dry-run")
    old = ligwf("slurm", "resubmit", study, *site)
    new = ligwf("resubmit", study, "--executor", "slurm", *site)
    assert old == new and old.returncode == 0, old.stderr
    assert "1 case(s) still queued or running" in new.stdout      # task 2 runs
    (line,) = [x for x in new.stdout.splitlines() if x.startswith("resubmitting")]
    assert line.startswith("resubmitting 3 case(s): 0 ") and " 2 " not in line, line
    # the follow-up job: the same function on the same options
    from ligwf.cli.main import build_parser
    from ligwf.cli.slurm import cmd_next_round

    words = [str(study), "--no-snapshots", "--templates", str(study), "--allow-unstable"]
    old_args = vars(build_parser().parse_args(["slurm", "next-round", *words]))
    new_args = vars(build_parser().parse_args(["next-round", *words, "--executor", "slurm"]))
    assert FOLLOW_UP["slurm"] is old_args["func"] is cmd_next_round
    options = {"study_dir", "no_snapshots", "templates", "allow_unstable", "mesh_cache"}
    assert options <= set(old_args) and new_args["executor"] == "slurm"
    assert {k: new_args[k] for k in options} == {k: old_args[k] for k in options}
    for command, here in (("resubmit", "the command that ran the study resumes"),
                          ("next-round", "--until-decided' takes the looks")):
        res = ligwf(command, study)
        assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1
        assert f"--executor = 'local': ligwf {command} hands a study" in res.stderr
        assert here in res.stderr
    # a study never run --until-decided: next-round refuses (it would submit a round 1)
    for words in (("slurm", "next-round", study), ("next-round", study, "--executor", "slurm")):
        res = ligwf(*words)
        assert res.returncode == 2 and len(res.stderr.strip().splitlines()) == 1
        assert "no rounds record (rounds.json)" in res.stderr, res.stderr
    assert not list((study / "slurm").glob("*.sh"))   # dry runs and refusals: no script


@pytest.mark.parametrize("executor", ["local", "slurm"])
def test_a_study_folder_as_workflow_goes_on_in_rounds_only(ligwf, study, executor):
    """WORKFLOW may be a study folder with --until-decided on either executor (its stored
    workflow); without it, one line and nothing written."""
    plain = ligwf("study", study, "--out", study, "--executor", executor,
                  *(["--dry-run"] if executor == "slurm" else []))
    assert plain.returncode == 2 and len(plain.stderr.strip().splitlines()) == 1
    assert "a study folder, not a workflow file" in plain.stderr
    if executor == "slurm":
        rounds = ligwf("study", study, "--out", study, "--executor", "slurm",
                       "--until-decided", "--dry-run")
        assert rounds.returncode == 0, rounds.stderr
        assert "#SBATCH --array=0-3" in rounds.stdout and "slurm next-round" in rounds.stdout
    assert not (study / "slurm").exists()
