"""Run a rendered study on Slurm: submit its case array and the analysis job, report
status, resubmit what did not finish.

The study folder is the single source of truth. Besides the case folders and the study
record (:mod:`ligwf.study`) it gets ``slurm/``: the batch scripts exactly as
submitted, ``slurm/logs/`` (``%A_%a`` logs) and ``slurm/jobs.json``, the list of
submissions (kind, job id, case indices, script, command, time), rewritten atomically
after every successful ``sbatch``. A case's outcome is its runner manifest
(:meth:`ligwf.study.case.CaseFolder.manifest`); Slurm's view (squeue, then ``scontrol show
job`` while the controller remembers the job) only says whether a task is still queued or
running.

Scripts and commands are built by :mod:`ligwf.slurm.script`, scheduler text is parsed by
:mod:`ligwf.slurm.parse`; this module does the I/O between them.
"""

from __future__ import annotations

import getpass
import json
import re
import shutil
import subprocess
from dataclasses import asdict, dataclass, field, fields, replace
from datetime import datetime, timezone
from pathlib import Path, PurePosixPath
from typing import Callable, Iterable, Mapping, Sequence

from ligwf import __version__
from ligwf.errors import ConfigError, SubmitError
from ligwf.fsio import atomic_write_json, atomic_write_text
from ligwf.scheduler import JobRound
from ligwf.study import layout
from ligwf.study.manifest import MISSING, read_manifest
from ligwf.study.study import Study
from ligwf.slurm.walltime import nodes_for
from ligwf.slurm.parse import (FINISHED_STATES, is_unknown_job, parse_sbatch_parsable,
                               parse_squeue, task_records)
from ligwf.slurm.script import (ScriptContext, analysis_array_script,
                                analysis_merge_script, analysis_script, array_script,
                                sbatch_command, scontrol_command, squeue_command)
from ligwf.slurm.site import SlurmSite, load_slurm_site

#: kinds of planned jobs that are arrays the job after them waits for
ARRAY_KINDS = ("array", "analysis-array")
Runner = Callable[[Sequence[str]], subprocess.CompletedProcess]


def require_scheduler() -> None:
    """SubmitError unless sbatch is on the PATH (checked before anything is written)."""
    if shutil.which("sbatch") is None:
        raise SubmitError("sbatch not found: is this a Slurm login node? "
                          "(use --dry-run to see the scripts without submitting)")


def run_command(argv: Sequence[str]) -> subprocess.CompletedProcess:
    """Run a scheduler command, capturing text; a missing command is a SubmitError."""
    if shutil.which(argv[0]) is None:
        raise SubmitError(f"{argv[0]} not found: is this a Slurm login node? "
                          "(use --dry-run to see the scripts without submitting)")
    try:
        return subprocess.run(list(argv), capture_output=True, text=True, timeout=120,
                              stdin=subprocess.DEVNULL)
    except subprocess.TimeoutExpired:
        raise SubmitError(f"{' '.join(argv)} did not answer within 120 s") from None


# ---------------------------------------------------------------------------------------
# the study folder
# ---------------------------------------------------------------------------------------

def read_record(study_dir: Path) -> list[dict]:
    """The submissions recorded in ``slurm/jobs.json`` (oldest first; [] when none)."""
    path = Path(study_dir) / layout.SLURM_RECORD
    if not path.is_file():
        return []
    return list(json.loads(path.read_text()).get("submissions", []))


def append_record(study_dir: Path, entry: dict) -> None:
    """Add one submission to ``slurm/jobs.json`` (atomic rewrite)."""
    subs = read_record(study_dir) + [entry]
    atomic_write_json(Path(study_dir) / layout.SLURM_RECORD, {"ligwf_version": __version__,
                                                      "submissions": subs})


def job_name(study_name: str, kind: str) -> str:
    """``ligwf-<study>`` / ``ligwf-<study>-analysis``, restricted to safe characters."""
    base = re.sub(r"[^A-Za-z0-9_.-]+", "-", study_name).strip("-") or "study"
    return f"ligwf-{base}" if kind == "array" else f"ligwf-{base}-{kind}"


# ---------------------------------------------------------------------------------------
# planning and submitting
# ---------------------------------------------------------------------------------------

@dataclass(frozen=True)
class PlannedJob:
    """A script to write and submit; ``after_array`` makes it depend on the array job(s).

    ``site``: the settings this script was built with (an array of a planned study has
    its own ``ntasks``); ``planned``: its ranks came from the rank plan (a resubmit plans
    again, on ``plan_cores``), not from ``--ntasks`` / the site setting; ``nodes``: the
    ``--nodes`` each array task asks for (None: not asked, Slurm places the ranks);
    ``steps``: the ligwf commands a follow-up job runs; ``study_round``: the round of a
    sequential study the job belongs to (:mod:`ligwf.pipeline.submit_rounds`). Both are
    recorded with the submission."""

    kind: str  # "array", "analysis", "analysis-array" or "analysis-merge"
    script_path: Path
    script_text: str
    indices: tuple[int, ...] = ()
    after_array: bool = False
    site: SlurmSite | None = None
    planned: bool = False
    plan_cores: int | None = None
    nodes: int | None = None
    steps: tuple[str, ...] = ()
    study_round: int | None = None


def plan_jobs(study_dir: Path, study_name: str, site: SlurmSite,
              request: JobRound) -> list[PlannedJob]:
    """The array job over the request's ``indices`` and (if it names ``post_steps``) its
    analysis job (pure). No ``indices``: the follow-up job alone, depending on nothing.
    ``study_round`` is recorded with every job (the round of a sequential study they run).

    ``analysis_tasks`` > 1 (a big study): the ``analyse`` step is split over an array of
    that many analysis tasks, after the case arrays, and the merge job after them runs the
    remaining steps (``report``): :func:`plan_analysis_array` with staging ``token``, the
    same scripts and tables as ``ligwf analyse --slurm N``.

    ``ranks`` (case index -> MPI ranks, from the rank plan): one array per rank count,
    widest first, each with ``--ntasks`` of its cases (``array-R-npK.sh``; ``array-R.sh``
    when all cases share one count); the analysis job waits for all of them. Without
    ``ranks`` every case gets ``site.ntasks`` in one array. Planned arrays ask for
    ceil(ntasks / ``site.cores_per_node``) nodes when the cores per node are known; an
    array on ``--ntasks`` / the site's ntasks asks for tasks only, as before."""
    study = PurePosixPath(Path(study_dir).resolve())
    idx, ranks = request.indices, request.ranks
    round_no = request.round_no if request.round_no is not None else next_round(study_dir)
    analysis_steps, study_round = request.post_steps, request.study_round
    plan_cores, analysis_tasks, token = (request.plan_cores, request.analysis_tasks,
                                         request.token)
    array_ctx = ScriptContext(study, job_name(study_name, "array"), __version__)
    if not idx:
        classes: dict[int, Sequence[int]] = {}
    elif ranks is None:
        classes = {site.ntasks: idx}
    else:
        missing = [i for i in idx if i not in ranks]
        if missing:
            raise ConfigError(f"rank plan: no ranks for case index(es) {missing}")
        classes = {}
        for i in idx:
            classes.setdefault(int(ranks[i]), []).append(i)
    jobs = []
    for ntasks in sorted(classes, reverse=True):
        members = tuple(classes[ntasks])
        job_site = replace(site, ntasks=ntasks)
        nodes = nodes_for(ntasks, site.cores_per_node) if ranks is not None else None
        name = layout.slurm_array_script(round_no, None if len(classes) == 1 else ntasks)
        jobs.append(PlannedJob("array", Path(study) / layout.SLURM_DIR / name,
                               array_script(array_ctx, job_site, members, nodes), members,
                               site=job_site, planned=ranks is not None,
                               plan_cores=plan_cores if ranks is not None else None,
                               nodes=nodes, study_round=study_round))
    if analysis_steps and (analysis_tasks > 1 or token) and "analyse" in analysis_steps:
        if token is None:
            raise ConfigError("a split analysis needs a staging token")
        rest = [step for step in analysis_steps if step != "analyse"]
        split = plan_analysis_array(study_dir, study_name, site, analysis_tasks, token, rest)
        jobs += [replace(split[0], after_array=bool(idx), study_round=study_round),
                 replace(split[1], steps=tuple(rest), study_round=study_round)]
    elif analysis_steps:
        ctx = ScriptContext(study, job_name(study_name, "analysis"), __version__)
        jobs.append(PlannedJob("analysis", Path(study) / layout.SLURM_DIR
                               / layout.slurm_analysis_script(round_no),
                               analysis_script(ctx, site, analysis_steps), idx,
                               after_array=bool(idx), steps=tuple(analysis_steps),
                               study_round=study_round))
    return jobs


def plan_analysis_array(study_dir: Path, study_name: str, site: SlurmSite, count: int,
                        token: str, steps: Sequence[str] = ()) -> list[PlannedJob]:
    """A split analysis (pure): the array of ``count`` analysis tasks and the merge job
    after it (``afterany``: the merge names a task that failed), scripts named by the
    token (``analysis-array-TOKEN.sh``, ``analysis-merge-TOKEN.sh``)."""
    study = PurePosixPath(Path(study_dir).resolve())
    ctx = ScriptContext(study, job_name(study_name, "analysis"), __version__)
    return [PlannedJob("analysis-array", Path(study) / layout.SLURM_DIR
                       / layout.slurm_analysis_array_script(token),
                       analysis_array_script(ctx, site, count, token),
                       tuple(range(count)), site=site),
            PlannedJob("analysis-merge", Path(study) / layout.SLURM_DIR
                       / layout.slurm_analysis_merge_script(token),
                       analysis_merge_script(ctx, site, count, token, steps),
                       after_array=True, site=site)]


def dry_run_text(jobs: Sequence[PlannedJob]) -> str:
    """What ``--dry-run`` prints: each script, then the sbatch command that would submit it."""
    arrays = sum(1 for job in jobs if job.kind in ARRAY_KINDS)
    names = (["<array job id>"] if arrays == 1
             else [f"<array job id {n}>" for n in range(1, arrays + 1)])
    out: list[str] = []
    ids: list[str] = []                     # the arrays before a job: what it waits for
    for job in jobs:
        cmd = sbatch_command(job.script_path)
        if job.after_array:
            cmd.insert(2, "--dependency=afterany:" + ":".join(ids))
        if job.kind in ARRAY_KINDS:
            ids.append(names[len(ids)])
        out += [f"# ----- {job.script_path} -----", job.script_text.rstrip("\n"),
                f"# would run: {' '.join(cmd)}", ""]
    return "\n".join(out)


def submit_jobs(study_dir: Path, jobs: Sequence[PlannedJob], site: SlurmSite,
                run: Runner = run_command) -> list[dict]:
    """Write each script, ``sbatch --parsable`` it, record the id; returns the new entries.

    The array id is recorded before the analysis job is submitted, so a failing second
    sbatch never loses the first id.
    """
    (Path(study_dir) / layout.SLURM_LOG_DIR).mkdir(parents=True, exist_ok=True)
    entries: list[dict] = []
    array_ids: list[str] = []
    for job in jobs:
        atomic_write_text(job.script_path, job.script_text)
        job.script_path.chmod(0o755)
        if job.after_array and not array_ids:
            raise SubmitError("analysis job planned without an array job")
        after = ":".join(array_ids) if job.after_array else None   # the arrays before it
        cmd = sbatch_command(job.script_path, array_ids if job.after_array else None)
        out = run(cmd)
        if out.returncode != 0:
            raise SubmitError(f"{' '.join(cmd)} exited {out.returncode}: "
                              f"{(out.stderr or out.stdout).strip()}")
        job_id = parse_sbatch_parsable(out.stdout)
        if job.kind in ARRAY_KINDS:
            array_ids.append(job_id)
        entry = {"kind": job.kind, "job_id": job_id, "indices": list(job.indices),
                 "script": str(job.script_path.relative_to(Path(study_dir).resolve())),
                 "command": cmd, "after": after,
                 "site": asdict(job.site or site),
                 "submitted": datetime.now(timezone.utc).isoformat(timespec="seconds")}
        if job.planned:
            entry["planned"] = {"cores": job.plan_cores}
        if job.steps:
            entry["steps"] = list(job.steps)
        if job.study_round is not None:
            entry["study_round"] = job.study_round
        append_record(study_dir, entry)
        entries.append(entry)
    return entries


def recorded_plan(study_dir: Path) -> dict | None:
    """``{"cores": N or None}`` if the latest array submission took its ranks from the
    rank plan (a resubmit then plans again), else None."""
    arrays = [s for s in read_record(study_dir) if s.get("kind") == "array"]
    return arrays[-1].get("planned") if arrays else None


def recorded_site(study_dir: Path) -> dict:
    """Site settings of the latest array submission (resubmits reuse them), {} if none."""
    arrays = [s for s in read_record(study_dir) if s.get("kind") == "array" and s.get("site")]
    return dict(arrays[-1]["site"]) if arrays else {}


def submitted_site(study_dir: Path) -> SlurmSite:
    """The site settings of the study's latest array submission (a resubmit, a follow-up
    job and ``cancel`` keep them); the site's own (:func:`load_slurm_site`) when it records
    none."""
    values = recorded_site(study_dir)
    if not values:
        return load_slurm_site()
    names = {f.name for f in fields(SlurmSite)}
    return SlurmSite(**{k: tuple(v) if isinstance(v, list) else v
                        for k, v in values.items() if k in names})


def next_round(study_dir: Path) -> int:
    """1 + the number of array submissions recorded so far (names the scripts)."""
    return 1 + sum(1 for s in read_record(study_dir) if s.get("kind") == "array")


# ---------------------------------------------------------------------------------------
# status
# ---------------------------------------------------------------------------------------

@dataclass
class CaseStatus:
    """One case: the runner's verdict and Slurm's view of its latest array task."""

    index: int
    case_id: str
    manifest: str  # the manifest status, or MISSING
    reason: str = ""
    job: str | None = None  # "<array id>_<index>" of the latest submission
    slurm_state: str | None = None  # PENDING/RUNNING/... or None when Slurm forgot it

    @property
    def queued(self) -> bool:
        """Still pending or running in Slurm (it will write its manifest itself)."""
        return self.slurm_state is not None and self.slurm_state.split()[0] not in FINISHED_STATES


@dataclass
class StudyStatus:
    cases: list[CaseStatus]
    jobs: list[dict] = field(default_factory=list)  # record entries + "state"
    scheduler_error: str | None = None  # why Slurm's view is missing (tolerant mode)


def slurm_view(job_ids: Iterable[str], run: Runner = run_command,
               user: str | None = None) -> dict[tuple[str, int | None], str]:
    """State per (job id, task index) from squeue, completed by ``scontrol show job``."""
    ids = [str(j) for j in job_ids]
    states: dict[tuple[str, int | None], str] = {}
    if not ids:
        return states
    out = run(squeue_command(user or getpass.getuser()))
    if out.returncode != 0:
        raise SubmitError(f"squeue exited {out.returncode}: {out.stderr.strip()}")
    for e in parse_squeue(out.stdout):
        key = (e.array_job_id, e.array_task_id) if e.array_task_id is not None else (e.job_id, None)
        states[key] = e.state
    for job_id in ids:
        sc = run(scontrol_command(job_id))
        if sc.returncode != 0:
            if is_unknown_job(sc.stdout + sc.stderr):
                continue
            raise SubmitError(f"scontrol show job {job_id} exited {sc.returncode}: "
                              f"{sc.stderr.strip()}")
        for rec in task_records(sc.stdout):
            key = (rec.array_job_id, rec.array_task_id) if rec.array_job_id else (rec.job_id, None)
            states.setdefault(key, rec.state)
    return states


def study_status(study_dir: Path, run: Runner = run_command, user: str | None = None,
                 tolerant: bool = False) -> StudyStatus:
    """Every case with its manifest state and its latest task's Slurm state.

    With ``tolerant`` an unreachable scheduler leaves the Slurm states empty and says why
    (for ``status``); without it, it is an error (``resubmit`` must not guess what is
    still queued, or a case could run twice).
    """
    study_dir = Path(study_dir)
    study = Study.open(study_dir)
    record = read_record(study_dir)
    latest: dict[int, str] = {}
    for sub in record:
        if sub.get("kind") == "array":
            for i in sub.get("indices", []):
                latest[int(i)] = str(sub["job_id"])
    scheduler_error = None
    try:
        states = slurm_view([s["job_id"] for s in record], run, user)
    except SubmitError as exc:
        if not tolerant:
            raise
        states, scheduler_error = {}, str(exc)
    cases = []
    for index, (case_id, case_dir) in enumerate(zip(study.case_ids, study.case_dirs)):
        man = read_manifest(case_dir)
        job_id = latest.get(index)
        cases.append(CaseStatus(
            index=index, case_id=case_id,
            manifest=man.status if man else MISSING,
            reason=man.reason if man else "",
            job=f"{job_id}_{index}" if job_id else None,
            slurm_state=states.get((job_id, index)) if job_id else None))
    jobs = []
    for sub in record:
        entry = dict(sub)
        if sub.get("kind") != "array":
            state = states.get((str(sub["job_id"]), None))
            entry["state"] = state
            entry["active"] = state is not None and state.split()[0] not in FINISHED_STATES
            entry["completed"] = state is not None and state.split()[0] == "COMPLETED"
        jobs.append(entry)
    return StudyStatus(cases, jobs, scheduler_error)
