"""The executor registry (ligwf.executors): executors are picked by name, each from its own
frozen settings; an unknown name or another executor's settings is one line; and the one
wait loop of the executors."""

from __future__ import annotations

import dataclasses
import threading
import time

import pytest

from ligwf.errors import ConfigError
from ligwf.executors import EXECUTORS, LOCAL, build_executor, executor_kind, study_executor
from ligwf.local import LocalExecutor, RunSettings
from ligwf.scheduler import Executor, Scheduler, wait_for
from ligwf.slurm.jobs import append_record
from ligwf.slurm.scheduler import SlurmScheduler
from ligwf.slurm.site import SlurmSite


def test_every_executor_is_built_by_name_from_its_frozen_settings():
    assert tuple(EXECUTORS) == (LOCAL, "slurm")
    for name in EXECUTORS:
        kind = executor_kind(name)
        assert kind.name == name
        assert dataclasses.is_dataclass(kind.settings)
        assert kind.settings.__dataclass_params__.frozen, name
        executor = build_executor(name, kind.settings())
        assert isinstance(executor, Executor) and executor.name == name


def test_the_executors_are_the_local_runner_and_the_slurm_scheduler():
    local = build_executor(LOCAL, RunSettings(nprocs=3))
    assert type(local) is LocalExecutor and local.settings.nprocs == 3
    assert not isinstance(local, Scheduler)         # it runs now, it submits nothing
    slurm = build_executor("slurm", SlurmSite(partition="debug"))
    assert type(slurm) is SlurmScheduler and slurm.site.partition == "debug"
    assert isinstance(slurm, Scheduler)


def test_the_site_settings_take_the_overrides(monkeypatch, tmp_path):
    monkeypatch.setenv("LIGWF_SITE", str(tmp_path / "none.yaml"))
    monkeypatch.setenv("LIGWF_SLURM_PARTITION", "from-env")
    assert build_executor("slurm").site.partition == "from-env"
    kind = executor_kind("slurm")
    assert kind.site_settings(partition="given", account=None).partition == "given"
    assert executor_kind(LOCAL).site_settings(nprocs=2, cores=5).cores == 5


@pytest.mark.parametrize("name", ["pbs", "", "Slurm", "LOCAL"])
def test_an_unknown_name_is_one_line_naming_the_field_value_and_names(name):
    with pytest.raises(ConfigError) as err:
        build_executor(name)
    assert str(err.value) == (f"--executor = {name!r}: no such executor (allowed: "
                              "local, slurm)")
    with pytest.raises(ConfigError, match=r"^executor = 'pbs': no such executor"):
        executor_kind("pbs", field="executor")


def test_another_executors_settings_are_refused():
    with pytest.raises(ConfigError, match=r"^--executor = 'slurm': its settings are "
                                          r"SlurmSite, got RunSettings$"):
        build_executor("slurm", RunSettings())
    with pytest.raises(ConfigError, match="its settings are RunSettings, got SlurmSite"):
        build_executor(LOCAL, SlurmSite())


def test_a_study_keeps_the_slurm_settings_it_was_submitted_with(monkeypatch, tmp_path):
    monkeypatch.setenv("LIGWF_SITE", str(tmp_path / "none.yaml"))
    monkeypatch.setenv("LIGWF_SLURM_PARTITION", "site")
    study = tmp_path / "study"
    study.mkdir()
    assert study_executor("slurm", study).site.partition == "site"    # nothing recorded
    append_record(study, {"kind": "array", "job_id": "7", "site": dataclasses.asdict(
        SlurmSite(partition="recorded", modules=("openmpi/4.1",), ntasks=4))})
    site = study_executor("slurm", study).site
    assert (site.partition, site.modules, site.ntasks) == ("recorded", ("openmpi/4.1",), 4)
    assert type(study_executor(LOCAL, study)) is LocalExecutor


def test_the_one_wait_loop_asks_until_nothing_is_pending():
    answers = iter([True, True, False])
    assert wait_for(lambda: next(answers), threading.Event(), 0.001) is False
    # stopped without a way to cancel: returns at once, asked once
    stop = threading.Event()
    stop.set()
    asked = []
    assert wait_for(lambda: asked.append(1) or True, stop, 0.001) is True and asked == [1]
    # stopped with one: cancels once, then waits until what ran has ended
    left, cancelled = [5], []

    def pending() -> bool:
        left[0] -= 1
        return left[0] > 0
    assert wait_for(pending, stop, 0.001, lambda: cancelled.append(1)) is True
    assert cancelled == [1] and left == [0]
    # a stop set while it waits interrupts the wait (no full poll interval slept)
    later = threading.Event()
    threading.Timer(0.05, later.set).start()
    t0 = time.monotonic()
    assert wait_for(lambda: True, later, 30.0) is True
    assert time.monotonic() - t0 < 10
