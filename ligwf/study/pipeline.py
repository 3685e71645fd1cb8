"""The pipeline of a study, assembled once: prepare -> run -> analyse -> report.

Every path goes through these functions, so they cannot drift apart:

* ``ligwf study`` = :func:`prepare_workflow` + :func:`write` + :func:`run_study` +
  :func:`postprocess`;
* ``ligwf run`` / ``run-case`` = the first three / :func:`run_study` on one case;
* ``ligwf slurm submit`` = :func:`prepare_workflow` (pre-flight before anything is
  written or submitted) + :func:`write`; its array tasks run ``ligwf run-case`` and its
  analysis job runs :data:`POSTPROCESS_COMMANDS`, which are :func:`analyse_study` and
  :func:`report_study`: the two steps of :func:`postprocess`.

The science of the post-processing (steady window, bond criterion, GSD settings) is read
from the study (:attr:`ligwf.study.study.Study.analysis`, stored from the workflow's
``analysis:`` block), never passed in, so the local and the Slurm path compute the same
tables. What callers choose is only how things run (ranks, ensembles, outputs).
"""

from __future__ import annotations

import threading
from dataclasses import dataclass
from pathlib import Path
from typing import TYPE_CHECKING, Iterable, Sequence

from ligwf.engine.ensemble import run_ensemble
from ligwf.engine.health import DONE
from ligwf.engine.launch import Monitor, run_case
from ligwf.engine.site import EngineConfig
from ligwf.scene.workflow import load_workflow
from ligwf.study.case import CaseFolder
from ligwf.study.manifest import case_busy
from ligwf.study.prepare import Prepared, prepare, write_study
from ligwf.study.study import Study

if TYPE_CHECKING:  # the analysis and report stages load numba / matplotlib: imported on use
    from ligwf.analysis.runner import AnalysisOptions

#: Seconds between looks at cases another runner holds (see :func:`run_study`).
WAIT_SECONDS = 1.0

#: The ligwf sub-commands the Slurm analysis job runs over the study, in order: the CLI
#: faces of :func:`analyse_study` and :func:`report_study`, i.e. :func:`postprocess`.
POSTPROCESS_COMMANDS = ("analyse", "report")


@dataclass(frozen=True)
class RunSettings:
    """How the run stage runs (not what it computes)."""

    nprocs: int = 1                 # MPI ranks per case
    ensemble: int = 0               # > 0: all cases in ONE mpirun of this many ranks
    retry_unstable: bool = False
    template_dirs: tuple[Path, ...] = ()


def prepare_workflow(workflow: Path, overrides: Sequence[str] = (),
                     template_dirs: Iterable[Path] = (), allow_unstable: bool = False) -> Prepared:
    """Load and validate a workflow, render every case in memory and pre-flight it
    (UnstableCase on a refusal unless ``allow_unstable``). Writes nothing."""
    return prepare(load_workflow(workflow, list(overrides)), tuple(template_dirs),
                   allow_unstable)


def write(prepared: Prepared, out: Path, mesh_cache: Path | None = None) -> Study:
    """Write the prepared study folder (identical cases are rewritten byte for byte, so
    their outputs stay and a re-run resumes)."""
    return write_study(prepared.workflow, prepared.rendered, out, mesh_cache)


def all_done(cases: Iterable[CaseFolder]) -> bool:
    """Whether every case's manifest says done."""
    return all((m := c.manifest()) is not None and m.status == DONE for c in cases)


def run_study(study: Study, cases: Sequence[CaseFolder], engine: EngineConfig,
              settings: RunSettings = RunSettings(), monitor: Monitor | None = None,
              stop: threading.Event | None = None) -> bool:
    """Run ``cases`` of ``study`` (skipping finished ones, resuming killed ones): one after
    the other, or as one MPI ensemble. Returns whether all of them are done.

    Several runners may work on one study: each case runs in one of them (a per-case
    lock, :func:`ligwf.study.manifest.case_lock`); a runner that has finished its share
    waits for the cases the others hold, so every runner returns once the study is done."""
    stop = stop or threading.Event()
    if settings.ensemble:
        run_ensemble(study.path, list(cases), settings.ensemble, settings.nprocs, engine,
                     retry_unstable=settings.retry_unstable, stop=stop, monitor=monitor)
    else:
        def one(case: CaseFolder) -> None:
            run_case(case, settings.nprocs, engine, monitor, stop, settings.retry_unstable,
                     settings.template_dirs)

        for case in cases:
            if stop.is_set():
                break
            one(case)
        # cases another `ligwf run` holds: wait for them, and take over any whose runner
        # stops before it is done (its lock goes with it)
        busy = [c for c in cases if case_busy(c.path)]
        while busy and not stop.wait(WAIT_SECONDS):
            for case in [c for c in busy if not case_busy(c.path)]:
                one(case)
            busy = [c for c in cases if case_busy(c.path)]
    return all_done(cases)


def analyse_study(path: Path, out: Path | None = None,
                  options: "AnalysisOptions | None" = None, comm=None) -> dict | None:
    """Granules, frame and GSD tables of a study (or one case folder) with the study's
    analysis settings; ``options`` only say how it runs. Returns the analysis record on
    rank 0 (None on other MPI ranks)."""
    from ligwf.analysis.runner import AnalysisOptions, analyse

    return analyse(path, out, options or AnalysisOptions(), comm)


def report_study(path: Path, out: Path | None = None, snapshots: bool = True) -> Path:
    """Flow metrics (the study's steady window) and the report folder; returns it."""
    from ligwf.report.write import write_report

    return write_report(Study.open(path), out, snapshots=snapshots)


def postprocess(path: Path, snapshots: bool = True) -> tuple[dict | None, Path]:
    """Analyse, then report, a study with its stored settings: what ``ligwf study`` does
    after the run and what the Slurm analysis job does (:data:`POSTPROCESS_COMMANDS`)."""
    record = analyse_study(path)
    return record, report_study(path, snapshots=snapshots)
