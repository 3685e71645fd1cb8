"""Pure builders of Slurm batch scripts and scheduler command lines (no I/O, no Slurm).

Everything a submission sends to Slurm is built here from plain values, so golden tests
(tests/golden/slurm/) pin the exact text and unit tests pin the exact argv, without a
scheduler. :mod:`ligwf.slurm.jobs` writes the scripts and runs the commands.

Design notes
- All ``#SBATCH`` options live in the script, not on the sbatch command line: the script in
  the study folder is then a complete record of what was asked for.
- ``#!/bin/bash``: ``sbatch --wrap`` would run /bin/sh (dash on Debian).
- Log names use ``%A_%a`` (array job id, task index), so a resubmitted case gets a new log
  instead of overwriting the old one.
- Each array task ``exec``s ``ligwf run-case`` so the signals Slurm sends on ``scancel`` or
  at the time limit reach the runner directly (it then lets LIGGGHTS write its forced
  restart).
"""

from __future__ import annotations

import re
import shlex
from dataclasses import dataclass
from pathlib import PurePosixPath
from typing import Iterable, Sequence

from ligwf.errors import ConfigError
from ligwf.slurm.site import SlurmSite
from ligwf.study.layout import STUDY_FILE, SLURM_LOG_DIR
from ligwf.study.paths import control_character, path_text_problem, shown

#: squeue columns ligwf reads: job id, array job id, array task id, state, reason.
SQUEUE_FORMAT = "%i|%F|%K|%T|%r"


#: a Slurm job name ligwf writes (:func:`ligwf.slurm.jobs.job_name` keeps to these)
_JOB_NAME = re.compile(r"^[A-Za-z0-9_.-]+$")
#: a staging token of a split analysis (``ligwf.analysis.parts``)
_TOKEN = re.compile(r"^[A-Za-z0-9_-]+$")
#: characters of a study path Slurm reads differently from a shell in ``#SBATCH
#: --output=``: ``%`` starts a file name pattern (``%x`` is the job name), ``\`` escapes
#: even inside quotes (and ``\\`` switches every pattern off)
_SLURM_SPECIAL = {"%": "a percent sign (Slurm's file name patterns: %j, %x, ...)",
                  "\\": "a backslash (an escape in Slurm's #SBATCH parser)"}


def study_path_problem(study_dir: PurePosixPath | str) -> str | None:
    """Why ``study_dir`` cannot go into a batch script (None: it can): not absolute (a
    task's working folder is not the submitting one; a leading ``-`` would read as an
    option), not one line of text, or holding a character Slurm reads otherwise."""
    text = str(study_dir)
    if (why := path_text_problem(text)) is not None:
        return why
    if not text.startswith("/"):
        return "not an absolute path"
    for ch, what in _SLURM_SPECIAL.items():
        if ch in text:
            return f"holds {what}; rename the folder or use another --out"
    return None


@dataclass(frozen=True)
class ScriptContext:
    """What a script needs besides the site settings (all paths absolute). Refuses (one
    line, :class:`ConfigError`) a study path or job name that could become script text
    other than the one value it stands for."""

    study_dir: PurePosixPath
    job_name: str
    ligwf_version: str

    def __post_init__(self) -> None:
        why = study_path_problem(self.study_dir)
        if why is not None:
            raise ConfigError(f"study folder {shown(str(self.study_dir))}: {why}; a Slurm "
                              "script names it on its #SBATCH and command lines")
        if not _JOB_NAME.match(self.job_name):
            raise ConfigError(f"job name {self.job_name!r}: allowed characters are letters, "
                              "digits and _ . -")


def array_spec(indices: Iterable[int], max_concurrent: int | None = None) -> str:
    """Slurm ``--array`` value for exactly ``indices``: runs compressed, ``%K`` appended.

    >>> array_spec([0, 1, 2, 3], 2)
    '0-3%2'
    >>> array_spec([1, 3, 4, 5, 9])
    '1,3-5,9'
    """
    values = sorted(set(indices))
    if not values:
        raise ConfigError("a job array needs at least one case index")
    if values[0] < 0:
        raise ConfigError(f"array index {values[0]} is negative (allowed range [0, inf))")
    parts: list[str] = []
    start = prev = values[0]
    for v in values[1:] + [None]:  # type: ignore[operator]
        if v is not None and v == prev + 1:
            prev = v
            continue
        parts.append(str(start) if start == prev else f"{start}-{prev}")
        if v is not None:
            start = prev = v
    spec = ",".join(parts)
    if max_concurrent is not None:
        if max_concurrent < 1:
            raise ConfigError(f"max_concurrent = {max_concurrent}: allowed range [1, inf)")
        spec += f"%{max_concurrent}"
    return spec


def _q(value: str | PurePosixPath) -> str:
    return shlex.quote(str(value))


def _directives(site: SlurmSite, job_name: str, output: str, time: str | None,
                ntasks: int, extra: Sequence[str], nodes: int | None = None) -> list[str]:
    lines = [f"#SBATCH --job-name={job_name}", *extra, f"#SBATCH --ntasks={ntasks}"]
    if nodes is not None:
        lines.append(f"#SBATCH --nodes={nodes}")
    if time:
        lines.append(f"#SBATCH --time={time}")
    if site.partition:
        lines.append(f"#SBATCH --partition={site.partition}")
    if site.account:
        lines.append(f"#SBATCH --account={site.account}")
    lines.append(f"#SBATCH --output={_q(output)}")
    lines += [f"#SBATCH {arg}" for arg in site.sbatch_args]
    return lines


def _checked_steps(steps: Sequence[str]) -> Sequence[str]:
    """The ligwf steps of a follow-up job (``report``, or a shell-quoted ``slurm
    next-round --templates DIR ...``): each one line of text."""
    for step in steps:
        if (ch := control_character(step)) is not None:
            raise ConfigError(f"ligwf step {shown(step)}: holds {ch}; a step is one line")
    return steps


def _checked_token(token: str) -> str:
    if not _TOKEN.match(token):
        raise ConfigError(f"staging token {shown(token)}: allowed characters are letters, "
                          "digits, _ and -")
    return token


def _environment(site: SlurmSite) -> list[str]:
    lines: list[str] = []
    if site.modules:
        lines.append("module load " + " ".join(site.modules))
    lines += list(site.setup)
    return lines


def _launcher_env(site: SlurmSite) -> list[str]:
    """Tell the runner which launcher to use inside the allocation (see ligwf.engine.site).

    Nothing when the site sets no Slurm launcher: the engine settings then apply as they
    do for local runs (the job inherits the submitting environment).
    """
    if site.launcher is None:
        return []
    words = shlex.split(site.launcher)
    lines = [f"export LIGWF_MPIRUN={_q(words[0])}"]
    if len(words) > 1:
        lines.append(f"export LIGWF_MPIRUN_ARGS={_q(shlex.join(words[1:]))}")
    return lines


def array_script(ctx: ScriptContext, site: SlurmSite, indices: Iterable[int],
                 nodes: int | None = None) -> str:
    """The ``#!/bin/bash`` array script: one task per case index, running ``ligwf run-case``.

    ``nodes``: each task asks for exactly that many nodes (``--nodes``) besides its
    ``--ntasks``, so its ranks are not scattered over partly busy nodes; None leaves the
    placement to Slurm."""
    if nodes is not None and (isinstance(nodes, bool) or not isinstance(nodes, int)
                              or not 1 <= nodes <= site.ntasks):
        raise ConfigError(f"nodes = {nodes!r}: allowed range [1, ntasks = {site.ntasks}]")
    indices = sorted(set(indices))
    study = ctx.study_dir
    log = f"{study}/{SLURM_LOG_DIR}/{ctx.job_name}_%A_%a.out"
    lines = ["#!/bin/bash",
             *_directives(site, ctx.job_name, log, site.time, site.ntasks,
                          [f"#SBATCH --array={array_spec(indices, site.max_concurrent)}"],
                          nodes),
             f"# Written by ligwf {ctx.ligwf_version}: one array task per case of the study",
             f"# {study} (task id = case index in {STUDY_FILE}; {len(indices)} case(s)).",
             "set -eo pipefail",
             *_environment(site),
             *_launcher_env(site),
             f"cd {_q(study)}",
             'echo "ligwf: case ${SLURM_ARRAY_TASK_ID} of array ${SLURM_ARRAY_JOB_ID}'
             ' on $(hostname) with ${SLURM_NTASKS:-1} task(s) on ${SLURM_JOB_NUM_NODES:-1}'
             ' node(s): ${SLURM_JOB_NODELIST:-$(hostname)}"',
             f"exec {site.ligwf} run-case {_q(study)} --index \"$SLURM_ARRAY_TASK_ID\""
             ' --np "${SLURM_NTASKS:-1}"',
             ""]
    return "\n".join(lines)


def analysis_script(ctx: ScriptContext, site: SlurmSite, steps: Sequence[str]) -> str:
    """The follow-up job: ``ligwf <step> STUDY`` for each step (``analyse``, then ``report``).

    It runs after the array whatever the array's outcome (``afterany``): the analysis stage
    itself reads the manifests and uses only ``done`` cases.
    """
    if not steps:
        raise ConfigError("the analysis job needs at least one ligwf step")
    _checked_steps(steps)
    study = ctx.study_dir
    log = f"{study}/{SLURM_LOG_DIR}/{ctx.job_name}_%j.out"
    lines = ["#!/bin/bash",
             *_directives(site, ctx.job_name, log, site.analysis_time or site.time, 1, []),
             f"# Written by ligwf {ctx.ligwf_version}: analysis of the study {study}",
             "# after its case array has ended (submitted with --dependency=afterany).",
             "set -eo pipefail",
             *_environment(site),
             f"cd {_q(study)}",
             *[f"{site.ligwf} {step} {_q(study)}" for step in steps],
             ""]
    return "\n".join(lines)


def analysis_array_script(ctx: ScriptContext, site: SlurmSite, count: int, token: str) -> str:
    """The array of a split analysis: task K of ``count`` runs ``ligwf analyse STUDY
    --part K/count --token TOKEN`` (one partial output each, :mod:`ligwf.analysis.parts`)."""
    _checked_token(token)
    study = ctx.study_dir
    log = f"{study}/{SLURM_LOG_DIR}/{ctx.job_name}_%A_%a.out"
    lines = ["#!/bin/bash",
             *_directives(site, ctx.job_name, log, site.analysis_time or site.time, 1,
                          [f"#SBATCH --array={array_spec(range(count), site.max_concurrent)}"]),
             f"# Written by ligwf {ctx.ligwf_version}: the analysis of {study} split into",
             f"# {count} array task(s) (task K analyses share K; the merge job writes the tables).",
             "set -eo pipefail",
             *_environment(site),
             f"cd {_q(study)}",
             f"exec {site.ligwf} analyse {_q(study)} --part \"$SLURM_ARRAY_TASK_ID/{count}\""
             f" --token {_q(token)}",
             ""]
    return "\n".join(lines)


def analysis_merge_script(ctx: ScriptContext, site: SlurmSite, count: int, token: str,
                          steps: Sequence[str] = ()) -> str:
    """The job after a split analysis' array (``afterany``): ``ligwf analyse STUDY --merge
    count --token TOKEN`` (it names any task that left no part and fails), then ``ligwf
    <step> STUDY`` for each of ``steps`` (e.g. ``report``)."""
    _checked_token(token)
    _checked_steps(steps)
    study = ctx.study_dir
    log = f"{study}/{SLURM_LOG_DIR}/{ctx.job_name}_%j.out"
    lines = ["#!/bin/bash",
             *_directives(site, ctx.job_name, log, site.analysis_time or site.time, 1, []),
             f"# Written by ligwf {ctx.ligwf_version}: merge of the {count} analysis task(s)",
             f"# of {study} (submitted with --dependency=afterany on their array).",
             "set -eo pipefail",
             *_environment(site),
             f"cd {_q(study)}",
             f"{site.ligwf} analyse {_q(study)} --merge {count} --token {_q(token)}",
             *[f"{site.ligwf} {step} {_q(study)}" for step in steps],
             ""]
    return "\n".join(lines)


def sbatch_command(script: str | PurePosixPath,
                   after_any: str | Sequence[str] | None = None) -> list[str]:
    """``sbatch --parsable [--dependency=afterany:ID[:ID...]] SCRIPT`` as argv (one id, or
    several: a planned study has one array per rank count)."""
    cmd = ["sbatch", "--parsable"]
    if after_any is not None:
        ids = [after_any] if isinstance(after_any, str) else list(after_any)
        if not ids or not all(str(i).isdigit() for i in ids):
            raise ConfigError(f"dependency job id {after_any!r} is not a Slurm job id")
        cmd.append("--dependency=afterany:" + ":".join(str(i) for i in ids))
    return cmd + [str(script)]


def squeue_command(user: str) -> list[str]:
    """``squeue`` for all of ``user``'s jobs, one array task per line, ligwf's columns.

    Filtering by user instead of ``-j IDS`` keeps it working when a recorded id has already
    left the controller (``-j`` with an unknown id is an error on some Slurm versions).
    """
    return ["squeue", "-h", "-r", "-u", user, "-o", SQUEUE_FORMAT]


def scontrol_command(job_id: str) -> list[str]:
    """``scontrol -o show job ID``: one line per array task, while Slurm still knows it."""
    return ["scontrol", "-o", "show", "job", str(job_id)]


def scancel_command(job_id: str, task: int | None = None) -> list[str]:
    """``scancel ID`` or ``scancel ID_TASK``."""
    return ["scancel", f"{job_id}_{task}" if task is not None else str(job_id)]
