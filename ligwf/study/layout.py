"""The names of everything in a study folder, in one place.

A study folder (``ligwf render`` / ``run`` / ``study`` write it)::

    STUDY/study.json                 the workflow, its analysis settings, the case list
    STUDY/<case_id>/scene.json       original + scaled parameters and their content hash
    STUDY/<case_id>/manifest.json    what ran, how, and the verdict (the runner writes it)
    STUDY/<case_id>/run.log          screen of the current attempt (earlier: run.<n>.log)
    STUDY/<case_id>/thermo.csv       thermo table over all attempts
    STUDY/<case_id>/dumps.json       size and SHA-256 of every file in post/ when the run
                                     ended done (written with the done manifest)
    STUDY/<case_id>/post/, restart/  the engine's dumps and restarts
    STUDY/analysis/                  granule, GSD and flow tables
    STUDY/report/                    the report folder

Only :mod:`ligwf.study` opens these files by name; every stage asks its objects
(:class:`~ligwf.study.case.CaseFolder`, :class:`~ligwf.study.study.Study`).
"""

from __future__ import annotations

from pathlib import Path

#: Study level: the workflow, its analysis settings and the case list.
STUDY_FILE = "study.json"
#: Case level: original and scaled parameters plus the content hash.
SCENE_FILE = "scene.json"
#: Case level: the runner's record of the case.
MANIFEST_FILE = "manifest.json"
#: Case level: stdout+stderr of the current attempt (earlier attempts: ``run.<n>.log``).
SCREEN_FILE = "run.log"
#: Case level: thermo table over all attempts.
THERMO_FILE = "thermo.csv"
#: Case level: the dumps a finished run left (size and SHA-256 per file of ``post/``).
DUMP_RECORD = "dumps.json"
#: Case level: the engine's dump folder.
POST_DIR = "post"

#: Study level: outputs of the analysis stage.
ANALYSIS_DIR = "analysis"
#: Study level: the report folder.
REPORT_DIR = "report"

# files in ANALYSIS_DIR
ANALYSIS_RECORD = "analysis.json"
GRANULES_TABLE = "granules.parquet"
FRAMES_TABLE = "frames.csv"
GSD_TABLE = "gsd.csv"
GSD_SUMMARY_TABLE = "gsd_summary.csv"
GSD_POOLING_TABLE = "gsd_pooling.csv"
FLOW_TABLE = "flow.csv"
#: granule controls: each wet case beside its cohesionless twin, per definition
CONTROLS_TABLE = "controls.csv"
FLOW_PROFILES = "flow_profiles.json"


def is_study_folder(path: Path) -> bool:
    """Whether ``path`` holds a rendered study (its study record)."""
    return (Path(path) / STUDY_FILE).is_file()


def is_case_folder(path: Path) -> bool:
    """Whether ``path`` holds a rendered case (its scene record)."""
    return (Path(path) / SCENE_FILE).is_file()
