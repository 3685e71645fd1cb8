"""The pipeline of a study, assembled once: prepare -> run -> analyse -> report, or submit.

This package is the library entry point: the CLI (:mod:`ligwf.cli`) only parses arguments
and prints, a scheduler's jobs run ``ligwf run-case`` and :data:`POSTPROCESS_COMMANDS`, and
a notebook calls the same functions::

    from ligwf import pipeline
    prepared = pipeline.prepare_workflow(Path("workflows/demo.yaml"), ["sweep.cg_levels=[1,2]"])
    run = pipeline.start_run(prepared, Path("runs/demo"), pipeline.run_settings(cores=2))
    run.run()
    record, report_dir = pipeline.postprocess(run.study.path, run.executor)

* :mod:`~ligwf.pipeline.prepare` validates, scales, renders and pre-flights a workflow in
  memory, then writes the study folder;
* :mod:`~ligwf.pipeline.run` schedules the cases (:mod:`ligwf.engine.plan`) and runs them
  locally (mpirun, MPI ensembles, resume, several runners on one study);
* :mod:`~ligwf.pipeline.post` analyses and reports a study with its stored settings;
* :mod:`~ligwf.pipeline.submit` runs a study through a batch scheduler
  (:class:`ligwf.scheduler.Scheduler`, Slurm: :mod:`ligwf.slurm`), with the same
  preparation and the same planner;
* :mod:`~ligwf.pipeline.suite` writes the stability stress suite (every variant, refused
  cases included).

It is the top of the stages (docs/architecture.md, enforced by tests/test_architecture.py):
it imports every stage, no stage imports it.
"""

from ligwf.pipeline.post import POSTPROCESS_COMMANDS, analyse_study, postprocess, report_study
from ligwf.pipeline.prepare import Prepared, prepare, prepare_workflow, prepared_loads, write
from ligwf.local import RunSettings, run_settings
from ligwf.pipeline.run import (Interrupted, StudyRun, planned_schedule, run_case_of, run_study,
                                start_run)
from ligwf.pipeline.submit import (Resubmission, Submission, plan_resubmission, plan_submission,
                                   write_for_submit)

__all__ = ["POSTPROCESS_COMMANDS", "Interrupted", "Prepared", "Resubmission", "RunSettings",
           "StudyRun", "Submission", "analyse_study", "plan_resubmission", "plan_submission",
           "planned_schedule", "postprocess", "prepare", "prepare_workflow", "prepared_loads",
           "report_study", "run_case_of", "run_settings", "run_study", "start_run", "write",
           "write_for_submit"]
