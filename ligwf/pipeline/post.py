"""The post-processing stages of the pipeline: analyse, then report, a written study.

The science of the post-processing (steady window, bond criterion, GSD settings) is read
from the study (:attr:`ligwf.study.study.Study.analysis`, stored from the workflow's
``analysis:`` block), never passed in, so the local and the scheduler path compute the
same tables: ``ligwf study`` calls :func:`postprocess` after the run, a scheduler's
follow-up job runs :data:`POSTPROCESS_COMMANDS` (the CLI faces of :func:`analyse_study`
and :func:`report_study`, in that order).
"""

from __future__ import annotations

from pathlib import Path
from typing import TYPE_CHECKING

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

    return analyse(path, out, options or AnalysisOptions(), comm)


def report_study(path: Path, out: Path | None = None, snapshots: bool = True) -> Path:
    """Flow metrics (the study's steady window) and the report folder; returns it."""
    from ligwf.report.write import write_report

    return write_report(Study.open(path), out, snapshots=snapshots)


def postprocess(path: Path, snapshots: bool = True) -> tuple[dict | None, Path]:
    """Analyse, then report, a study with its stored settings: what ``ligwf study`` does
    after the run and what a scheduler's follow-up job does (:data:`POSTPROCESS_COMMANDS`)."""
    record = analyse_study(path)
    return record, report_study(path, snapshots=snapshots)
