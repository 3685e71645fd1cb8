"""How the local executor (ligwf.local) launches a study's cases: the rank plan by default,
--np / --ensemble as overrides. The launchers are replaced by recorders (no engine, no MPI): these tests pin
which launcher gets which cases on how many ranks, in which order."""

from __future__ import annotations

import threading

import pytest

import ligwf.local as local
from ligwf.engine.site import EngineConfig
from ligwf.pipeline.prepare import prepare_workflow, write
from ligwf.eligibility import eligible
from ligwf.local import LocalExecutor, RunSettings, study_schedule
from ligwf.pipeline.run import run_study
from ligwf.study.manifest import case_lock

from helpers import DRUM

# study order is the sweep order: the small cases first, so "longest first" shows
SMALL = ["sweep.cg_levels=[3,2]"]                        # 4 cases of 222-748 particles
WITH_BIG = ["sweep.cg_levels=[3,1]", "scene.drum.length=0.018"]  # CG1: ~12,000 particles


@pytest.fixture
def launches(monkeypatch):
    """Record run_case / run_ensemble calls instead of starting engines."""
    calls: list[tuple] = []

    def fake_run_case(case, nprocs, engine, monitor=None, stop=None, retry=False, dirs=()):
        calls.append(("mpirun", nprocs, case.path.name))

    def fake_run_ensemble(study, cases, nprocs, group_size, engine, retry_unstable=False,
                          stop=None, monitor=None, label="launch"):
        calls.append(("ensemble", nprocs, group_size, tuple(c.path.name for c in cases),
                      label.split("-")[0]))
        return {}

    monkeypatch.setattr(local, "run_case", fake_run_case)
    monkeypatch.setattr(local, "run_ensemble", fake_run_ensemble)
    monkeypatch.setattr(local, "take_over", lambda case: None)
    return calls


def make_study(tmp_path, overrides):
    prepared = prepare_workflow(DRUM, overrides)
    return write(prepared, tmp_path / "study", tmp_path / "meshes")


def run(study, settings):
    stop = threading.Event()
    return run_study(study, study.cases, LocalExecutor(settings, EngineConfig()), None, stop)


def test_planned_small_cases_run_side_by_side_longest_first(tmp_path, launches):
    study = make_study(tmp_path, SMALL)
    assert not run(study, RunSettings(nprocs=None, cores=2))
    assert launches == [("ensemble", 2, 1, ("cg2-weber-r0", "cg2-bond-r0", "cg3-weber-r0",
                                            "cg3-bond-r0"), "phase1")]


def test_planned_big_case_runs_first_on_two_ranks_then_the_rest_side_by_side(tmp_path,
                                                                              launches):
    study = make_study(tmp_path, WITH_BIG)
    assert study.cases[-1].scaled.particles.count > 6000
    run(study, RunSettings(nprocs=None, cores=2))
    assert launches == [("mpirun", 2, "cg1-none-r0"),
                        ("ensemble", 2, 1, ("cg3-weber-r0", "cg3-bond-r0"), "phase2")]


def test_planned_on_one_core_runs_one_case_after_the_other(tmp_path, launches):
    study = make_study(tmp_path, WITH_BIG)
    run(study, RunSettings(nprocs=None, cores=1))
    assert [c[:2] for c in launches] == [("mpirun", 1)] * 3
    assert launches[0][2] == "cg1-none-r0"                # longest first


def test_np_override_keeps_its_old_meaning(tmp_path, launches):
    study = make_study(tmp_path, SMALL)
    run(study, RunSettings(nprocs=2, cores=2))
    assert launches == [("mpirun", 2, c.path.name) for c in study.cases]   # study order


def test_ensemble_override_keeps_its_old_meaning(tmp_path, launches):
    study = make_study(tmp_path, WITH_BIG)
    run(study, RunSettings(nprocs=1, ensemble=2, cores=2))
    assert launches == [("ensemble", 2, 1, tuple(c.path.name for c in study.cases),
                         "launch")]


def test_a_planned_ensemble_leaves_out_the_cases_another_runner_holds(tmp_path, launches):
    study = make_study(tmp_path, SMALL)
    held = study.cases[0]
    phase = study_schedule(eligible(study.cases).to_run,
                           RunSettings(nprocs=None, cores=2)).phases[0]
    members = [c for c in study.cases]
    with case_lock(held.path) as mine:
        assert mine
        LocalExecutor(RunSettings(nprocs=None, cores=2)).ensemble_phase(
            study, members, phase, "phase1-x", EngineConfig(), None, threading.Event(),
            lambda case, n: launches.append(("mpirun", n, case.path.name)))
    assert launches == [("ensemble", 2, 1, tuple(c.path.name for c in members[1:]), "phase1")]


def test_a_planned_ensemble_with_one_free_case_runs_it_alone(tmp_path, launches):
    study = make_study(tmp_path, SMALL)
    members = list(study.cases)
    phase = study_schedule(members, RunSettings(nprocs=None, cores=2)).phases[0]
    with case_lock(members[0].path), case_lock(members[1].path), case_lock(members[2].path):
        LocalExecutor(RunSettings(nprocs=None, cores=2)).ensemble_phase(
            study, members, phase, "phase1-x", EngineConfig(), None, threading.Event(),
            lambda case, n: launches.append(("mpirun", n, case.path.name)))
    assert launches == [("mpirun", 1, members[3].path.name)]


def test_settings_say_when_they_are_planned():
    assert RunSettings(nprocs=None).planned
    assert not RunSettings(nprocs=2).planned
    assert not RunSettings(nprocs=None, ensemble=2).planned
    assert not RunSettings().planned                  # library default: one rank, as before
