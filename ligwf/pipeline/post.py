"""The post-processing stages of the pipeline: analyse, then report, a written study.

The science of the post-processing (steady window, bond criterion, GSD settings) is read
from the study (:attr:`ligwf.study.study.Study.analysis`, stored from the workflow's
``analysis:`` block), never passed in, so the local and the scheduler path compute the
same tables: ``ligwf study`` calls :func:`postprocess` after the run, a scheduler's
follow-up job runs :data:`POSTPROCESS_COMMANDS` (the CLI faces of :func:`analyse_study`
and :func:`report_study`, in that order).
"""

from __future__ import annotations

import dataclasses

from pathlib import Path
from typing import TYPE_CHECKING

from ligwf.errors import ConfigError
from ligwf.fsio import writing_in
from ligwf.scene.accept import AcceptSettings, build_accept_settings
from ligwf.scene.workflow import apply_override, parse_override
from ligwf.scheduler import Executor
from ligwf.study.paths import check_inside
from ligwf.study.study import Study

if TYPE_CHECKING:  # the analysis and report stages load numba / matplotlib: imported on use
    from ligwf.analysis.runner import AnalysisOptions

#: The ligwf sub-commands a scheduler's follow-up job runs over the study, in order: the
#: CLI faces of :func:`analyse_study` and :func:`report_study`, i.e. :func:`postprocess`.
POSTPROCESS_COMMANDS = ("analyse", "report")


def analyse_study(path: Path, out: Path | None = None,
                  options: "AnalysisOptions | None" = None, comm=None) -> dict | None:
    """Granules, frame and GSD tables of a study (or one case folder) with the study's
    analysis settings; ``options`` only say how it runs. Returns the analysis record on
    rank 0 (None on other MPI ranks)."""
    from ligwf.analysis.runner import AnalysisOptions, analyse

    if out is None:         # the study's own analysis folder: no link leading out of it
        study = Study.open(path)
        check_inside(study.path, [study.analysis_dir])
    with writing_in(Path(out) if out is not None else Path(path)):
        return analyse(path, out, options or AnalysisOptions(), comm)


def report_study(path: Path, out: Path | None = None, snapshots: bool = True,
                 accept_overrides: tuple[str, ...] = ()) -> Path:
    """Flow metrics (the study's steady window) and the report folder; returns it.
    ``accept_overrides`` (``accept.angle_deg=2``, ...) re-decide the verdict under another
    budget from the stored analysis (validated before anything is written)."""
    from ligwf.report.digests import record_digests
    from ligwf.report.write import write_report

    study = Study.open(path)
    if accept_overrides:
        study = dataclasses.replace(study, accept=overridden_accept(study.accept,
                                                                    accept_overrides))
    if out is None:         # the study's own report folder: no link leading out of it
        check_inside(study.path, [study.report_dir])
    with writing_in(Path(out) if out is not None else study.report_dir):
        folder = write_report(study, out, snapshots=snapshots)
        record_digests(folder)      # what the API's check() holds the tables against
    return folder


def overridden_accept(accept: AcceptSettings, overrides: tuple[str, ...]) -> AcceptSettings:
    """The budget with ``--set accept.KEY=VALUE`` applied; any other key is refused in one
    line (the report re-decides; the runs and the analysis stay what they were)."""
    raw = {"accept": accept.model_dump(mode="json")}
    for text in overrides:
        key, value = parse_override(text)
        if key.split(".")[0] != "accept" or key.count(".") != 1:
            raise ConfigError(f"--set {key}: ligwf report only re-decides the budget: "
                              "accept.<criterion>=VALUE (the rest needs a new run or analysis)")
        apply_override(raw, key, value)
    return build_accept_settings(raw["accept"], "accept")


def postprocess(path: Path, executor: Executor, snapshots: bool = True,
                analysis_tasks: int = 1) -> tuple[dict | None, Path]:
    """Analyse on ``executor`` (in ``analysis_tasks`` shares), then report, a study with its
    stored settings: what ``ligwf study`` does after the run and what a scheduler's
    follow-up job does (:data:`POSTPROCESS_COMMANDS`)."""
    record = executor.analyse(Study.open(path), analysis_tasks)
    return record, report_study(path, snapshots=snapshots)
