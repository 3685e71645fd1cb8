"""The names of everything in a study folder, in one place.

A study folder (``ligwf render`` / ``run`` / ``study`` write it)::

    STUDY/study.json                 the workflow, its analysis settings, the case list
    STUDY/<case_id>/scene.json       original + scaled parameters and their content hash
    STUDY/<case_id>/manifest.json    what ran, how, and the verdict (the runner writes it)
    STUDY/<case_id>/run.log          screen of the current attempt (earlier: run.<n>.log)
    STUDY/<case_id>/thermo.csv       thermo table over all attempts
    STUDY/<case_id>/dumps.json       size and SHA-256 of every file in post/ when the run
                                     ended done (written with the done manifest)
    STUDY/<case_id>/extension.json   production added by a sequential study (optional)
    STUDY/<case_id>/post/, restart/  the engine's dumps and restarts
    STUDY/<case_id>/.runner.lock     held by the one runner working on the case
    STUDY/.ensemble/<phase>-<n>/     an ensemble launch's scratch: launch.log, queue.json,
                                     claims/ (one claim per case)
    STUDY/slurm/                     job scripts, jobs.json (the submissions), logs/
    STUDY/rounds.json                the looks of a sequential study (optional)
    STUDY/analysis/                  granule, GSD, kinetics and flow tables, the steady
                                     window, the analysis record, per case a granule series
    STUDY/report/                    tables, summary.md, index.html, figures/, paraview/

Every file and folder name ligwf writes or reads is declared here and nowhere else
(engine scratch, the scheduler's files, a stability suite's and a calibration's records
included; tests/analysis/records/test_records_contract.py checks every module): the study
folder's files are opened by :mod:`ligwf.study` (every stage asks its objects,
:class:`~ligwf.study.case.CaseFolder`, :class:`~ligwf.study.study.Study`); the analysis
stage (:mod:`ligwf.analysis`) owns the files of ``analysis/`` and the report stage
(:mod:`ligwf.report`) those of ``report/``, each writing them once.
"""

from __future__ import annotations

import re
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
#: Case level: production added to the rendered run (``ligwf study --until-decided``):
#: the run continues from its restarts; the scene and its hash stay the rendered ones.
EXTENSION_FILE = "extension.json"
#: Study level: the looks of a sequential study (``ligwf study --until-decided``).
ROUNDS_FILE = "rounds.json"
#: Study level: held while one process takes a look or submits a round of a sequential
#: study on a scheduler (``ligwf slurm next-round``), so two never do it at once.
ROUNDS_LOCK = ".rounds.lock"
#: Case level: the engine's dump folder.
POST_DIR = "post"
#: Case level: the engine's restart folder.
RESTART_DIR = "restart"
#: Case level: the folders the engine writes into (made before it starts).
OUTPUT_DIRS = (POST_DIR, RESTART_DIR)
#: Case level: the periodic restarts of the drum input, written alternately (the names the
#: template ``templates/drum.in.j2`` writes them under).
PERIODIC_RESTARTS = (f"{RESTART_DIR}/restart_a.liggghts", f"{RESTART_DIR}/restart_b.liggghts")
#: Case level: suffix of a restart's identity sidecar (``<restart>.id.json``).
RESTART_SIDECAR_SUFFIX = ".id.json"
#: Case level: the lock a runner holds while it runs the case (released by the kernel).
RUNNER_LOCK = ".runner.lock"
#: Case level: the engine's own log file (LIGGGHTS ``-log``).
ENGINE_LOG = "log.liggghts"
#: Case level: the input of a resumed attempt (next to ``INPUT_NAME``).
RESUME_INPUT = "resume.in.liggghts"
#: Case level: the main LIGGGHTS input (the renderer writes it).
INPUT_NAME = "in.liggghts"
#: Case level: the drum mesh (the input refers to it by this name).
MESH_NAME = "drum.stl"

#: Study level: the scratch folder of an ensemble phase (one MPI launch running many cases).
ENSEMBLE_DIR = ".ensemble"
#: in ``ENSEMBLE_DIR``: the launcher's screen, the cases to claim, one claim file per case
ENSEMBLE_LOG = "launch.log"
ENSEMBLE_QUEUE = "queue.json"
ENSEMBLE_CLAIMS_DIR = "claims"
#: glob of the claim files in ``ENSEMBLE_CLAIMS_DIR``
ENSEMBLE_CLAIM_GLOB = "*.json"
#: Study level: the Slurm job scripts, their record and their logs (``ligwf slurm``).
SLURM_DIR = "slurm"
SLURM_LOG_DIR = f"{SLURM_DIR}/logs"
SLURM_RECORD = f"{SLURM_DIR}/jobs.json"
#: Study level: the screens of the analysis shares a local executor runs side by side
#: (:meth:`ligwf.local.LocalExecutor.analyse`), one per share: :func:`analysis_share_log`.
ANALYSIS_SHARE_LOG_DIR = ".analysis-shares"
#: Suite level: the stability suite's record (``ligwf stability``).
SUITE_RECORD = "suite.json"
#: Calibration folder (``ligwf calibrate``): the measured candidates, the study of the wet
#: reference and the study of the candidates
CALIBRATION_TABLE = "calibration.csv"
CALIBRATION_REFERENCE_DIR = "wet"
CALIBRATION_CANDIDATES_DIR = "candidates"
#: Default mesh cache (``LIGWF_MESH_CACHE`` or ``--mesh-cache`` to say otherwise).
MESH_CACHE_DIR = "meshes"

#: Study level: outputs of the analysis stage.
ANALYSIS_DIR = "analysis"
#: Study level: the report folder.
REPORT_DIR = "report"

# ---- files in ANALYSIS_DIR (written by the analysis stage, read by the report)
#: what was analysed, from what, with which settings, and the digest of every table
ANALYSIS_RECORD = "analysis.json"
GRANULES_TABLE = "granules.parquet"
FRAMES_TABLE = "frames.csv"
GSD_TABLE = "gsd.csv"
GSD_SUMMARY_TABLE = "gsd_summary.csv"
GSD_POOLING_TABLE = "gsd_pooling.csv"
#: the pooling table per condition and pool size (mean, min, max over pools)
GSD_POOLING_SUMMARY_TABLE = "gsd_pooling_summary.csv"
#: granule kinetics per case and frame, per condition with bands, definition sensitivity
KINETICS_TABLE = "kinetics.csv"
KINETICS_SUMMARY_TABLE = "kinetics_summary.csv"
SENSITIVITY_TABLE = "sensitivity.csv"
#: flow metrics per case (its steady window included)
FLOW_TABLE = "flow.csv"
#: granule controls: each wet case beside its cohesionless twin, per definition
CONTROLS_TABLE = "controls.csv"
#: the flow record: per case its steady window, per-frame series of every flow metric,
#: profiles, velocity field and the frames it read (:mod:`ligwf.analysis.records.flow`)
FLOW_PROFILES = "flow_profiles.json"
#: the cross-section fields of every case's steady window: per-frame kernel sums on the
#: grid (numpy archive, :mod:`ligwf.analysis.records.fields`)
FIELDS_DATA = "fields.npz"
#: per case ``ANALYSIS_DIR/<case_id>/``: the granule series (``.pvd``) of its labelled frames
GRANULE_SERIES = "granules.pvd"
#: glob of the labelled frames in a case's granule series folder
GRANULE_FRAME_GLOB = "granules_*.vtu"


def screen_log(attempt: int) -> str:
    """Case level: the screen of an earlier attempt (``SCREEN_FILE`` renamed when the next
    attempt starts)."""
    return f"run.{attempt}.log"


def particle_dump(step: int) -> str:
    """Case level, in ``POST_DIR``: the engine's particle dump of ``step``."""
    return f"particles_{step}.vtu"


#: globs of the engine's particle and contact dumps (also of a foreign run's dump folder)
PARTICLE_DUMP_GLOB = "particles_*.vtu"
CONTACT_DUMP_GLOB = "contacts_*.vtu"
#: the names of those dumps, their step as the group (the engine's bounding-box files,
#: ``particles_boundingBox_*``, do not match)
PARTICLE_DUMP_RE = re.compile(r"^particles_(\d+)\.vtu$")
CONTACT_DUMP_RE = re.compile(r"^contacts_(\d+)\.vtu$")
#: either of them: the dumps an analysis reads
ANALYSED_DUMP_RE = re.compile(r"^(particles|contacts)_\d+\.vtu$")
#: Case level: the restart a rank writes on SIGTERM (the engine's working folder), its step
#: as the group
FORCED_RESTART_RE = re.compile(r"^restart_forced_liggghts_(\d+)\.data$")
#: Case level: the current screen or an earlier attempt's (:func:`screen_log`)
SCREEN_LOG_RE = re.compile(r"^run(\.\d+)?\.log$")


def ensemble_claim(position: int) -> str:
    """The claim file of the case at ``position`` of an ensemble's queue."""
    return f"{position}.json"


def ensemble_claim_done(position: int) -> str:
    """The file saying the case at ``position`` of an ensemble's queue has ended."""
    return f"{position}.done"


def slurm_array_script(round_no: int, ntasks: int | None = None) -> str:
    """A round's case array job script; ``ntasks`` when the round has one array per rank
    count."""
    return f"array-{round_no}.sh" if ntasks is None else f"array-{round_no}-np{ntasks}.sh"


def slurm_analysis_script(round_no: int) -> str:
    """A round's analysis job script."""
    return f"analysis-{round_no}.sh"


def slurm_analysis_array_script(token: str) -> str:
    """The array job script of an analysis split over tasks (and its merge job's)."""
    return f"analysis-array-{token}.sh"


def slurm_analysis_merge_script(token: str) -> str:
    """The job script merging an analysis split over tasks."""
    return f"analysis-merge-{token}.sh"


def analysis_share_log(token: str, index: int) -> str:
    """The screen of share ``index`` of the local split analysis ``token``."""
    return f"share-{token}-{index}.log"


def staging_dir(token: str) -> str:
    """Folder (in an output folder) of a set of outputs being written, named by its token,
    before it replaces the old set."""
    return f".staging-{token}"


def replaced_dir(token: str) -> str:
    """Folder (in an output folder) the outputs a new set replaces are moved into before
    they are removed."""
    return f".replaced-{token}"


def ensemble_launch_dir(label: str, launch: int) -> str:
    """Folder (in ``ENSEMBLE_DIR``) of one launch of an ensemble phase."""
    return f"{label}-{launch}"


def mesh_file(key: str) -> str:
    """A drum mesh in the mesh cache, by its geometry key."""
    return f"drum_{key}.stl"


def granule_frame(step: int) -> str:
    """File name of the granule-labelled particles of one frame (in the case's folder)."""
    return f"granules_{step}.vtu"


def field_image(case_id: str) -> str:
    """File name of a case's window-mean fields as VTK ImageData (ParaView), in
    ``ANALYSIS_DIR``."""
    return f"fields_{case_id}.vti"


def granule_frame_step(name: str) -> int | None:
    """The step of a :func:`granule_frame` file name, None for any other name."""
    stem, dot, ext = name.partition(".")
    head, _, step = stem.partition("_")
    if head != "granules" or ext != "vtu" or not step.isdigit():
        return None
    return int(step)



def analysis_parts_dir(token: str) -> str:
    """Folder (in the analysis output folder) of the partial outputs of one analysis split
    over array tasks (``ligwf analyse --part``), named by its staging token."""
    return f".parts-{token}"


def analysis_part(index: int, count: int) -> str:
    """File name of array task ``index``'s partial output (of ``count`` tasks)."""
    return f"part-{index:05d}-of-{count:05d}.pkl"

# ---- files in REPORT_DIR (written by the report stage)
CASES_REPORT = "cases.csv"
CONDITIONS_REPORT = "conditions.csv"
NOISE_FLOOR_REPORT = "noise_floor.csv"
#: the verdict per sweep group, CG level, rule and criterion (ligwf.inference.verdict)
VERDICT_TABLE = "verdict.csv"
VERDICT_RECORD = "verdict.json"
#: the CG1 value extrapolated from the CG-n levels of each rule, beside the measured one
#: (ligwf.inference.reference)
EXTRAPOLATION_REPORT = "extrapolation.csv"
#: placed liquid's spreading rate per CG-n level against CG1 (ligwf.inference.spreading)
SPREADING_REPORT = "spreading.csv"
#: the cohesionless twins' field errors against the wet CG1 cases (ligwf.report.fields)
FIELD_NULL_REPORT = "fields_null_check.csv"
SUMMARY_REPORT = "summary.md"
HTML_REPORT = "index.html"
#: size and SHA-256 of every top-level report file, as the report wrote it (report.digests)
REPORT_FILES_RECORD = "report_files.json"
FIGURES_DIR = "figures"
#: glob of the figures in ``FIGURES_DIR``
FIGURE_GLOB = "*.png"
#: ParaView collections: ``PARAVIEW_DIR/<case_id>.pvd`` + ``PARAVIEW_DIR/<case_id>/drum_<step>.vtu``
PARAVIEW_DIR = "paraview"
FIGURE_ERROR_VS_RUNTIME = "error_vs_runtime.png"
FIGURE_VERDICT_FOREST = "verdict_forest.png"   # the verdict as one picture, first on the page
FIGURE_VELOCITY_PROFILES = "velocity_profiles.png"
FIGURE_GSD_OVERLAY = "gsd_overlay.png"
FIGURE_KINETICS = "granule_kinetics.png"
FIGURE_SENSITIVITY = "granule_sensitivity.png"
#: a sequential study's looks: every criterion's interval against its budget (report.rounds)
FIGURE_ROUNDS = "rounds.png"


def field_figure(name: str, kind: str) -> str:
    """File name of a field map figure (``name``: a condition or comparison tag,
    ``kind``: maps or differences)."""
    return f"fields_{name}_{kind}.png"


def snapshot_figure(case_id: str, coloured_by: str) -> str:
    """File name of a case's snapshot figure (``coloured_by``: speed or granules)."""
    return f"{case_id}_{coloured_by}.png"


def paraview_collection(case_id: str) -> str:
    """File name of a case's ParaView collection in ``PARAVIEW_DIR``."""
    return f"{case_id}.pvd"


def drum_frame(step: int) -> str:
    """File name of the drum mesh turned to its position at ``step``."""
    return f"drum_{step}.vtu"


#: a committed results folder's README, rendered from its tables (ligwf.api.results_folder)
RESULTS_README = "README.md"
#: a granule-growth run's measures (growth rows, shares per cadence, flow per frame),
#: pickled beside it by ligwf.analysis.granules.growth_study.measured
GROWTH_CACHE = ("growth-rows.pkl", "growth-shares.pkl", "growth-flow.pkl")


def is_study_folder(path: Path) -> bool:
    """Whether ``path`` holds a rendered study (its study record)."""
    return (Path(path) / STUDY_FILE).is_file()


def is_case_folder(path: Path) -> bool:
    """Whether ``path`` holds a rendered case (its scene record)."""
    return (Path(path) / SCENE_FILE).is_file()
