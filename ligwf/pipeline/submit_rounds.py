"""A sequential study on a batch scheduler (``ligwf study --executor slurm
--until-decided``): the rounds of :func:`ligwf.pipeline.rounds.until_decided`, each a
dependent array, driven by the same loop of rounds (:func:`ligwf.pipeline.rounds.drive`)
with a scheduler's acts (:func:`keep_going`).

The first submission writes the study and its rounds record
(:func:`~ligwf.pipeline.rounds.start_rounds`) and submits round 1: the case arrays and,
instead of the plain analysis job, a follow-up job running ``ligwf <scheduler>
next-round STUDY`` (:class:`FollowUp`). That job (:func:`keep_going` with ``take_looks``)
analyses and reports the study and takes the look
(:func:`~ligwf.pipeline.rounds.take_look`: written into the rounds record first); if the
study goes on it writes the next round's case folders and extensions exactly as the local
loop does (:func:`~ligwf.pipeline.rounds.write_round`) and submits the cases that must run
(:func:`~ligwf.eligibility.eligible`: new replicas and extended done cases, whose
manifest still reads ``done``; the same rule ``ligwf slurm resubmit`` and a local run
follow) with another follow-up job of the same kind; once it stops, the final report.

Where the study stands (:func:`progress`) is read from two records, never guessed: the
rounds record (k looks taken) and the scheduler's submission record, where every job
names the round it runs (``study_round``; r the latest, the round handed to the
scheduler); the decision is :func:`ligwf.pipeline.rounds.stand`, the same as the local
loop's:

* the last look stopped it: :data:`STOPPED` (only the final report remains, written
  once: :func:`~ligwf.eligibility.report_due`);
* r <= k: round k + 1 is :data:`ROUND_DUE` (written and submitted, tagged k + 1);
* r = k + 1 and a case still queued (or held by a live runner): :data:`RUNNING`;
* r = k + 1 and a case not done (failed, killed, unstable, extended, or its task never
  ran): :data:`INCOMPLETE`, no look (``ligwf slurm resubmit`` runs them again with a
  follow-up);
* r = k + 1 and every case done (:attr:`~ligwf.eligibility.Eligible.settled`): the
  :data:`LOOK_DUE`.

So a call after a kill, at any point, finds the state the last one left and completes it:
a look is taken only while it is due (then k = r and it is not due again) and a round is
submitted only while it is due (then r = k + 1). One process moves a study on at a time
(:func:`ligwf.study.rounds.rounds_lock`). A kill between a round's arrays and its
follow-up leaves the look due with no job to take it: ``resubmit`` then submits the
follow-up job alone.
"""

from __future__ import annotations

import shlex
import time
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Sequence

from ligwf.errors import ConfigError
from ligwf.pipeline.post import report_study
from ligwf.pipeline.prepare import Prepared
from ligwf.pipeline.rounds import (INCOMPLETE, LOOK_DUE, ROUND_DUE, RUNNING, STOPPED, Stand,
                                   drive, stand, take_look, write_round)
from ligwf.eligibility import Eligible, eligible, report_due
from ligwf.executors import LOCAL, build_executor
from ligwf.pipeline.submit import rerun_jobs
from ligwf.scheduler import Scheduler, queued_tasks
from ligwf.study.rounds import Look, Rounds, read_rounds, rounds_lock
from ligwf.study.study import Study

#: the sub-command of the follow-up job (``ligwf <scheduler> next-round STUDY``)
NEXT_ROUND = "next-round"


@dataclass(frozen=True)
class FollowUp:
    """How the rounds run on a scheduler: the follow-up job's options (snapshots in the
    final report, user templates and ``--allow-unstable`` to render added replicas as the
    first submission did) and how the cases get their ranks (``planned``: the rank plan
    on at most ``cores``; otherwise the site's fixed task count)."""

    scheduler: str
    planned: bool = True
    cores: int | None = None
    snapshots: bool = True
    template_dirs: tuple[Path, ...] = ()
    allow_unstable: bool = False
    retry_unstable: bool = False
    mesh_cache: Path | None = None

    @property
    def steps(self) -> list[str]:
        """The follow-up job's one command (after ``ligwf``, before the study folder)."""
        words = [self.scheduler, NEXT_ROUND]
        words += [] if self.snapshots else ["--no-snapshots"]
        for folder in self.template_dirs:
            words += ["--templates", str(Path(folder).resolve())]
        words += ["--allow-unstable"] if self.allow_unstable else []
        if self.mesh_cache is not None:
            words += ["--mesh-cache", str(Path(self.mesh_cache).resolve())]
        return [shlex.join(words)]

    @classmethod
    def from_steps(cls, steps: Sequence[str], planned: bool, cores: int | None) -> "FollowUp":
        """The settings a recorded follow-up job ran with (its :attr:`steps`)."""
        words = shlex.split(" ".join(steps))
        if len(words) < 2 or words[1] != NEXT_ROUND:
            raise ConfigError(f"{' '.join(steps)!r} is no follow-up job of a sequential study")
        templates = tuple(Path(w) for a, w in zip(words, words[1:]) if a == "--templates")
        meshes = [Path(w) for a, w in zip(words, words[1:]) if a == "--mesh-cache"]
        return cls(words[0], planned, cores, "--no-snapshots" not in words, templates,
                   "--allow-unstable" in words, mesh_cache=meshes[-1] if meshes else None)


def submitted_round(jobs: Sequence[dict]) -> int:
    """The latest round of a sequential study the scheduler's record names (0: none)."""
    return max((int(j["study_round"]) for j in jobs if j.get("study_round") is not None),
               default=0)


def is_sequential(jobs: Sequence[dict]) -> bool:
    """Whether the study was submitted ``--until-decided`` (its jobs name their rounds)."""
    return submitted_round(jobs) > 0


def recorded_steps(jobs: Sequence[dict]) -> list[str]:
    """The commands of the latest follow-up job of a sequential study ([]: none)."""
    runs = [j["steps"] for j in jobs if j.get("steps") and NEXT_ROUND in " ".join(j["steps"])]
    return list(runs[-1]) if runs else []


@dataclass(frozen=True)
class Progress:
    """Where a sequential study stands: its state, the looks taken, the round the state
    is about (due, running, incomplete or looked at), the jobs of its queued cases, the
    cases a runner would run that no job holds, the cases not done, and the follow-up
    jobs still queued or running (besides the caller's own)."""

    state: Stand
    looks: int
    round: int
    queued: tuple[str, ...] = ()
    unfinished: tuple[int, ...] = ()
    not_done: tuple[str, ...] = ()
    follow_ups: tuple[str, ...] = ()
    stop: str = ""


def progress(study_dir: Path, scheduler: Scheduler, retry_unstable: bool = False,
             own_job: str | None = None) -> Progress:
    """Where the sequential study in ``study_dir`` stands (module docstring)."""
    rounds = read_rounds(study_dir)
    st = scheduler.status(study_dir)        # not tolerant: never guess what still runs
    k, r = len(rounds.looks), submitted_round(st.jobs)
    follow = tuple(str(j["job_id"]) for j in st.jobs if j.get("kind") != "array"
                   and j.get("active") and str(j["job_id"]) != own_job)
    needs = (eligible(Study.open(study_dir).cases, retry_unstable, queued_tasks(st))
             if r == k + 1 and not rounds.stopped else Eligible(()))
    state = stand(rounds, r, needs, study_dir)
    if state == STOPPED:
        return Progress(STOPPED, k, k, follow_ups=follow, stop=rounds.looks[-1].stop)
    if state == ROUND_DUE:
        return Progress(ROUND_DUE, k, k + 1, follow_ups=follow)
    queued = tuple(t.queued for t in needs.tasks if t.queued is not None)
    not_done = tuple(t.case.case_id for t in needs.not_done)
    return Progress(state, k, r, queued, needs.indices, not_done, follow)


@dataclass(frozen=True)
class Moved:
    """What one call did: where the study stood at its end, the looks it took, the record
    entries of what it submitted and the cases they run, and one line saying so."""

    progress: Progress
    looks: tuple[Look, ...] = ()
    submitted: tuple[dict, ...] = ()
    indices: tuple[int, ...] = ()
    note: str = ""


def _submit(study: Study, scheduler: Scheduler, how: FollowUp, indices: Sequence[int],
            study_round: int | None) -> list[dict]:
    jobs = rerun_jobs(study, scheduler, sorted(indices), how.cores, how.planned, how.steps,
                      study_round=study_round)
    return scheduler.submit(study.path, jobs)


def keep_going(out: Path, scheduler: Scheduler, how: FollowUp,
               prepared: Callable[[], Prepared] | None = None,
               take_looks: bool = False, show: Callable[[Look, Rounds], None] | None = None,
               wait_seconds: float = 0.0, own_job: str | None = None) -> Moved:
    """Move the sequential study in ``out`` on by what its state asks for (module
    docstring), under the rounds lock: the loop of rounds of every executor
    (:func:`ligwf.pipeline.rounds.drive`) with a scheduler's acts.

    ``take_looks`` (the follow-up job): a due look is taken (``show`` prints it), a stopped
    study gets its final report, an incomplete round is left for ``resubmit``; cases still
    queued are waited for up to ``wait_seconds`` (a task that has just ended may still
    show as completing). Otherwise (``submit`` / ``resubmit`` on a login node): the
    unfinished cases of an incomplete round are submitted again with a follow-up job, and
    a due look gets a follow-up job of its own unless one is queued. A due round is
    written and submitted when ``prepared`` is given (it prepares the workflow as the
    first submission did; called only then); otherwise a follow-up job does it."""
    out = Path(out)
    with rounds_lock(out) as mine:
        if not mine:
            return Moved(progress(out, scheduler, how.retry_unstable, own_job),
                         note="another ligwf process is moving this study on: nothing done")
        looks: list[Look] = []
        deadline = time.monotonic() + wait_seconds
        now: Progress | None = None
        submitted: Moved | None = None

        def state() -> Stand:
            nonlocal now
            now = progress(out, scheduler, how.retry_unstable, own_job)
            return now.state

        def look() -> bool:
            if not take_looks:
                return False                # a login-node call: the follow-up job looks
            rounds = take_look(out, read_rounds(out), build_executor(LOCAL))
            looks.append(rounds.looks[-1])
            if show is not None:
                show(rounds.looks[-1], rounds)
            return True

        def hand_out() -> bool:
            nonlocal submitted
            if prepared is None:
                return False                # a follow-up job writes and submits it
            submitted = _submit_round(out, scheduler, how, prepared, now, take_looks)
            if submitted is None:           # nothing to run: look again at once
                return look()
            return False

        def settle() -> bool:
            # a task that has just ended may still show as queued: wait a little for it
            if not take_looks or time.monotonic() >= deadline:
                return False
            time.sleep(min(5.0, max(0.0, deadline - time.monotonic())))
            return True

        drive(state, {LOOK_DUE: look, ROUND_DUE: hand_out, RUNNING: settle,
                      INCOMPLETE: lambda: False})
        if submitted is not None:
            return Moved(submitted.progress, tuple(looks), submitted.submitted,
                         submitted.indices, submitted.note)
        return _settle(out, scheduler, how, now, take_looks, tuple(looks))


def _submit_round(out: Path, scheduler: Scheduler, how: FollowUp,
                  prepared: Callable[[], Prepared],
                  p: Progress, take_looks: bool) -> Moved | None:
    """Write round ``p.round`` (what the looks added) and submit its cases with a
    follow-up job; None when none must run and the caller takes the look itself."""
    study = write_round(prepared(), out, read_rounds(out), how.mesh_cache)
    indices = eligible(study.cases, how.retry_unstable,
                       queued_tasks(scheduler.status(out))).indices
    if not indices and take_looks:
        return None
    entries = _submit(study, scheduler, how, indices, p.round)
    what = (f"{len(indices)} case(s)" if indices else "no case to run: the follow-up job "
            "alone")
    return Moved(progress(out, scheduler, how.retry_unstable), (), tuple(entries),
                 tuple(indices), f"round {p.round} submitted: {what}")


def _settle(out: Path, scheduler: Scheduler, how: FollowUp, p: Progress, take_looks: bool,
            looks: tuple[Look, ...]) -> Moved:
    """The states a call ends in: the final report of a stopped study, or what a
    login-node call submits to keep the study going, or nothing with the reason."""
    if p.state == STOPPED:
        if take_looks and report_due(Study.open(out)):
            report_study(out, snapshots=how.snapshots)
        return Moved(p, looks, note=f"stopped at look {p.looks}: {p.stop}")
    names = ", ".join(p.not_done[:6]) + (" ..." if len(p.not_done) > 6 else "")
    if take_looks:
        if p.state == RUNNING:
            return Moved(p, looks, note=f"round {p.round} still runs ({len(p.queued)} case "
                         "task(s) queued): the follow-up job after them takes the look")
        if p.state == INCOMPLETE:
            return Moved(p, looks, note=f"round {p.round}: case(s) not done ({names}): no "
                         f"look; 'ligwf {how.scheduler} resubmit {out}' runs them again and "
                         "the look follows")
        raise ConfigError(f"{out}: round {p.round} is due but its workflow was not given")
    study = Study.open(out)
    if p.state in (INCOMPLETE, RUNNING) and p.unfinished:
        entries = _submit(study, scheduler, how, p.unfinished, p.round)
        return Moved(p, looks, tuple(entries), p.unfinished,
                     f"round {p.round}: {len(p.unfinished)} case(s) submitted again, the "
                     "look follows them")
    if p.state == RUNNING:
        return Moved(p, looks, note=f"round {p.round} still runs ({len(p.queued)} case "
                     "task(s) queued): its follow-up job takes the look")
    if p.state == INCOMPLETE:
        return Moved(p, looks, note=f"round {p.round}: case(s) not done and not to be run "
                     f"again ({names}; unstable? --include-unstable runs them again): no look")
    if p.follow_ups:
        return Moved(p, looks, note=f"the follow-up job {', '.join(p.follow_ups)} is still "
                     f"queued: it takes the look / submits round {p.round}")
    entries = _submit(study, scheduler, how, (), None)
    return Moved(p, looks, tuple(entries), (),
                 f"{'look ' + str(p.looks + 1) if p.state == LOOK_DUE else f'round {p.round}'}"
                 " is due: its follow-up job submitted")


