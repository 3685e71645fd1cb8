"""Studies that run until they decide (``ligwf study WORKFLOW --out DIR --until-decided``).

Rounds of run, analyse, verdict: after each look (:func:`plan_look`), the cheapest level
of each sweep group that can still pass (the fastest condition that does not fail) is
the round's target (with ``--every-level``: every level with an undecided criterion, so
that each level's error is decided, as a ladder study asks; an arm several levels share,
their CG1 runs, gets the most any of them asks, not the sum); each of its undecided criteria names the cheapest way to HALVE its
interval's half-width (:mod:`ligwf.inference.sampling`: more production on the runs
there are, or more replicas of an arm); the round does all of them (per arm the longest
extension and the most replicas asked for) and looks again, until the target meets the
budget, every level fails, the planned looks are spent or the next round would pass the
core-hour cap. A round halves the width rather than doing what item 4's "what would
decide" names (an amount computed from the measured difference): amounts chosen from the
difference bias the next look's test (on null synthetic studies, 10 % wrong fails at
alpha 0.05; halving, which depends on the variances only, stays within 5 %:
``benchmarks/bench_coverage.py``). A level of the study's answer (every level with
``--every-level``; else the levels that fail up to the one named) whose runs the verdict
flags as too short -- their steady windows start at the cap, so nothing was shown steady --
has those runs' arm extended by the planner's rule in the same round, before the study may
stop, even when every level is decided (:func:`too_short`).

Everything a round adds is first written into the study's rounds record
(:mod:`ligwf.study.rounds`), then done; so the same command after a kill (of ligwf, an
engine or mpirun, in any round) reads the record, re-applies what the last look asked for
(idempotent: an extension names its target step, a new replica its number), resumes the
runs (:mod:`ligwf.engine.resume`) and looks again: nothing lost, repeated or mixed. A
continued case keeps its manifest, thermo table and frame series
(:mod:`ligwf.study.extension`); a new replica is a new case folder with its own seeds.

Where a sequential study stands is decided once, for every executor (:func:`stand`), from
the rounds record, the round the executor was handed and what each case needs
(:func:`ligwf.eligibility.eligible`): stopped, a round due, running, incomplete, a look
due. One loop acts on it (:func:`drive`): here (:func:`until_decided`, on any
:class:`~ligwf.scheduler.Executor` that runs cases to their end) it runs each round and
asks again until the study stops; on a batch scheduler the follow-up job
(:mod:`ligwf.pipeline.submit_rounds`) drives the same loop with acts that submit the next
round with another follow-up job and end there.

Repeated looks: every look tests at alpha / max_looks (Bonferroni spending, stated in the
record and the report).
"""

from __future__ import annotations

import dataclasses
import math
from dataclasses import dataclass
from enum import StrEnum
from pathlib import Path
from typing import Callable, Mapping

from ligwf.inference.equivalence import UNDECIDED
from ligwf.errors import ConfigError
from ligwf.pipeline.post import postprocess, report_study
from ligwf.pipeline.prepare import Prepared, prepare, render_case, write
from ligwf.eligibility import HELD, Eligible, eligible
from ligwf.pipeline.run import StudyRun, scheduled, site_engine
from ligwf.analysis.records.flow import FlowRecord
from ligwf.inference.planning import calibration, capped_runs, noise_table, run_costs
from ligwf.inference.verdict import FAILS, MEETS, Verdict, is_control_group
from ligwf.inference.verdict_records import read_verdict
from ligwf.scheduler import Executor
from ligwf.scene.workflow import CONTROL_KEY, apply_override, expand, parse_override
from ligwf.study.case import group_of
from ligwf.study.condition import Arm, Condition
from ligwf.study.extension import write_extension
from ligwf.study import layout
from ligwf.study.ownership import check_own_folder
from ligwf.study.rounds import (CAPPED, DECIDED, EXTEND, LOOKS_SPENT, REPLICAS, STUCK, Action,
                                AddReplicas, ExtendProduction, Look, Rounds, read_rounds,
                                write_rounds)
from ligwf.study.study import Study


@dataclass(frozen=True)
class RoundPlan:
    """How a sequential study runs: at most ``max_looks`` looks and ``max_core_hours``
    core-hours of runs in all (None: no cap); ``every_level``: the rounds work on every
    level's undecided criteria (:attr:`~ligwf.study.rounds.Rounds.every_level`)."""

    max_looks: int = 3
    max_core_hours: float | None = None
    every_level: bool = False


def start_rounds(out: Path, plan: RoundPlan) -> Rounds:
    """The study's rounds record: created at the first look, and refused when a later call
    asks for another number of looks (its level was fixed before any data were seen). A
    last look that stopped because no planned way decided it (``stuck``) or because the cap
    was reached and the cap is now raised is taken again (same number, same data, same
    level: no new test) and plans the round it could not: the scope (``every_level``) or
    the cap of this call may plan one."""
    rounds = read_rounds(out)
    if rounds.looks and rounds.max_looks != plan.max_looks:
        raise ConfigError(f"--max-looks = {plan.max_looks}: this study was started with "
                          f"{rounds.max_looks} looks ({len(rounds.looks)} taken); each look "
                          "tests at alpha / looks, fixed before its first look: keep "
                          f"--max-looks {rounds.max_looks}")
    looks = rounds.looks
    last = looks[-1] if looks else None
    if last is not None and (last.stop_kind == STUCK or (last.stop_kind == CAPPED and (
            plan.max_core_hours is None
            or last.core_hours + last.planned_core_hours <= plan.max_core_hours))):
        # the cap was raised past the round it stopped, or it found no planned way: that
        # look is taken again (same number, same data, same level) and plans the round
        looks = looks[:-1]
    rounds = Rounds(plan.max_looks, rounds.alpha, plan.max_core_hours, looks,
                    plan.every_level)
    write_rounds(out, rounds)
    return rounds


def prepare_study_folder(path: Path, overrides=(), template_dirs=(),
                         allow_unstable: bool = False) -> Prepared:
    """Prepare the workflow a study folder stores (its study record), with ``--set``
    overrides: ``ligwf study DIR --out DIR --until-decided`` on an existing study."""
    raw = Study.workflow_of(path)
    for text in overrides:
        apply_override(raw, *parse_override(text))
    return prepare(expand(raw), tuple(template_dirs), allow_unstable)


# ---------------------------------------------------------------- what the rounds added
def added_cases(prepared: Prepared, rounds: Rounds) -> Prepared:
    """The prepared study with the replicas earlier rounds added (rendered in memory, in
    the order they were added, indices after the workflow's own cases). The added cases
    are the workflow's own expansion with more replicas at their CG levels
    (:meth:`~ligwf.scene.workflow.Workflow.with_replicas`), so each is the case the
    workflow would have had with that many replicas (its seeds, its scene); control
    twins are not added."""
    wanted = [(a.condition, r) for x in rounds.looks for a in x.actions
              if isinstance(a, AddReplicas) for r in a.replicas]
    if not wanted:
        return prepared
    counts: dict[float, int] = {}
    for condition, replica in wanted:
        counts[condition.cg] = max(counts.get(condition.cg, 0), replica + 1)
    more = prepared.workflow.with_replicas(counts)
    by_key = {(Condition(group_of(dict(c.varied)), c.cg, c.rule.value), c.replica): c
              for c in more.cases if CONTROL_KEY not in dict(c.varied)}
    have = {rc.case.case_id for rc in prepared.rendered}
    rendered = list(prepared.rendered)
    for key in wanted:
        case = by_key.get(key)
        if case is None or case.case_id in have:
            continue
        case = dataclasses.replace(case, index=len(rendered))
        rendered.append(render_case(case))
        have.add(case.case_id)
    return dataclasses.replace(prepared, rendered=rendered)


def apply_extensions(study: Study, rounds: Rounds) -> None:
    """Write every production extension the looks asked for (a case's newest target
    step wins; written only where it differs, so a repeat changes nothing)."""
    target: dict[str, int] = {}
    new: dict[tuple[Condition, int], int] = {}
    for x in rounds.looks:
        for a in x.actions:
            if isinstance(a, ExtendProduction):
                target.update(a.run_steps)
            else:
                new.update(((a.condition, rep), a.each_run_steps) for rep in a.replicas)
    for case in study.cases:
        steps = target.get(case.case_id, new.get((Condition.of(case), case.replica)))
        if steps is not None and steps != case.scaled.numerics.run_steps:
            base = case.rendered_scaled.numerics.run_steps
            write_extension(case.path, base, max(steps, base), case.scaled.numerics.dt)


# ---------------------------------------------------------------- one look
def spent_core_hours(study: Study) -> float:
    """Core-hours the study's runs have cost (sum over the manifests' attempts)."""
    total = 0.0
    for case in study.cases:
        m = case.manifest()
        total += (m.core_seconds if m is not None else 0.0)
    return total / 3600.0


def _criteria_rows(verdict: Verdict) -> tuple[dict, ...]:
    return tuple({"condition": c.name, "group": g.group, "criterion": r.name, "label": r.label,
                  "unit": r.unit, "state": r.state, "value": r.value, "lo": r.lo, "hi": r.hi,
                  "budget": r.budget}
                 for g in verdict.groups for c in g.conditions for r in c.criteria
                 if r.assessed)


def _needs(criteria, condition: Condition, needs: dict[Condition, list[float]]) -> None:
    """Add to ``needs`` (per arm, named by the condition whose runs it is: [seconds of
    production more per run, replicas more]) what the undecided ``criteria`` of
    ``condition`` ask for; an arm shared by several conditions (their CG1 runs) gets the
    most any of them asks, not the sum."""
    for r in criteria:
        for arm in Arm.named_in(r.round_arm):
            need = needs.setdefault(condition.side(arm), [0.0, 0])
            if r.round_by == EXTEND:
                need[0] = max(need[0], r.round_amount)
            elif r.round_by == REPLICAS:
                amount = r.round_amount if arm == Arm.CG_N else r.round_amount_cg1
                need[1] = max(need[1], int(amount) if math.isfinite(amount) else 0)


def _actions(study: Study, needs: dict[Condition, list[float]]) -> tuple[list[Action], float]:
    """The round's actions on each arm ``needs`` names (longer production on its runs,
    then new replicas as long as them) and their planned core-hours (the planner's rates
    calibrated by the arm's own runs,
    :func:`~ligwf.inference.planning.calibration`)."""
    actions: list[Action] = []
    hours = 0.0
    for condition, (extend, add) in needs.items():
        cases = [c for c in study.cases if condition.covers(c)]
        if not cases:
            continue
        rate = calibration(cases)
        steps_now = max(c.scaled.numerics.run_steps for c in cases)
        if extend > 0:
            more = math.ceil(extend / cases[0].scaled.numerics.dt)
            actions.append(ExtendProduction(
                condition.arm, extend, tuple(c.case_id for c in cases),
                {c.case_id: steps_now + more for c in cases}))
            hours += rate * sum(run_costs(c.scaled)[1] * extend for c in cases) / 3600.0
            steps_now += more
        if add > 0:
            first = max(c.replica for c in cases) + 1
            # new replicas run as long as the arm's runs (extended ones included)
            actions.append(AddReplicas(condition, tuple(range(first, first + add)),
                                       steps_now))
            scaled = cases[0].scaled.with_run_steps(steps_now)
            hours += rate * add * run_costs(scaled)[0] / 3600.0
    return actions, hours


def _by_speed(group) -> list:
    """A sweep group's conditions, fastest first (a level without a speedup last)."""
    return sorted(group.conditions,
                  key=lambda c: -c.speedup if math.isfinite(c.speedup) else math.inf)


def _targets(group, every_level: bool) -> list:
    """The conditions of a sweep group a round works on: the cheapest level that can still
    pass (none once it meets the budget), or with ``every_level`` each level with an
    undecided criterion."""
    by_speed = _by_speed(group)
    if every_level:
        return [c for c in by_speed if any(r.state == UNDECIDED for r in c.criteria)]
    open_ = [c for c in by_speed if c.state != FAILS]
    return [] if not open_ or open_[0].state == MEETS else open_[:1]


def _answer_levels(group, every_level: bool) -> list:
    """The conditions of a sweep group whose states make the study's answer: every level
    with ``every_level``; else, fastest first, the levels that fail up to the first that
    does not (the one named, or the one still open)."""
    if every_level:
        return list(group.conditions)
    out = []
    for c in _by_speed(group):
        out.append(c)
        if c.state != FAILS:
            break
    return out


def too_short(study: Study, verdict: Verdict, every_level: bool = False
              ) -> dict[Condition, float]:
    """Per arm (named by the condition whose runs it is) of a level in the study's answer
    (:func:`_answer_levels`) that the verdict flags as too short (its steady windows start
    at their cap), the production each of its capped runs needs at least
    (:func:`ligwf.analysis.records.steady_window.least_extension`, the most any of them
    needs). A decision on such runs is not shown steady, so a round extends them before
    the study stops, whatever the level's state; control groups are left out."""
    conditions = [c.condition for g in verdict.groups
                  if not is_control_group(g.group)
                  for c in _answer_levels(g, every_level) if c.too_short]
    path = study.analysis_dir / layout.FLOW_PROFILES
    if not conditions or not path.is_file():
        return {}
    flow = FlowRecord.read(path)
    usable = [case for case in study.cases if case.case_id in flow.cases]   # those analysed
    noise = noise_table(usable, flow, ())
    needs: dict[Condition, float] = {}
    for side in {c.side(arm) for c in conditions for arm in Arm}:
        _, more = capped_runs(noise, [case.case_id for case in usable if side.covers(case)])
        if more > 0:
            needs[side] = more
    return needs


def plan_look(verdict: Verdict, study: Study, rounds: Rounds, number: int) -> Look:
    """The look ``number`` of ``verdict``: what the next round does, or why the study stops.
    Runs too short to show a steady state (:func:`too_short`) are extended first, in the
    same round as the targets' needs, even when every level is decided."""
    base = dict(number=number, alpha=rounds.alpha_per_look,
                core_hours=spent_core_hours(study), criteria=_criteria_rows(verdict))
    targets, needs, stuck = [], {}, []
    for g in verdict.groups:
        if is_control_group(g.group) or not g.conditions:
            continue
        for c in _targets(g, rounds.every_level):
            undecided = [r for r in c.criteria if r.state == UNDECIDED]
            planned = [r for r in undecided if r.round_by]
            stuck += [f"{c.name} {r.label}: {r.note}" for r in undecided if not r.round_by]
            stuck += [] if undecided else [f"{c.name}: no criterion of the budget assessed"]
            if planned:
                _needs(planned, c.condition, needs)
                targets.append(c.name)
    short = too_short(study, verdict, rounds.every_level)
    for condition, more in short.items():
        need = needs.setdefault(condition, [0.0, 0])
        need[0] = max(need[0], more)
    if short:
        stuck = []          # the round that extends them is the planned way
        targets += [f"{c.name} (runs too short)" for c in sorted(short, key=lambda c: c.key)
                    if not any(t == c.name for t in targets)]
    actions, hours = _actions(study, needs)
    if not targets:
        why = ("decided: " + "; ".join(g.sentence for g in verdict.groups
                                       if not is_control_group(g.group))) if not stuck else (
            "no planned way to decide " + "; ".join(stuck))
        return Look(**base, stop=why, stop_kind=STUCK if stuck else DECIDED)
    if number >= rounds.max_looks:
        return Look(**base, target=", ".join(targets), stop_kind=LOOKS_SPENT, stop=(
            f"the {rounds.max_looks} planned looks are spent; undecided: the next round "
            f"would have been {hours:.2g} core-h on {', '.join(targets)}"))
    cap = rounds.max_core_hours
    if cap is not None and base["core_hours"] + hours > cap:
        return Look(**base, target=", ".join(targets), planned_core_hours=hours,
                    stop_kind=CAPPED, stop=(
            f"the cap of {cap:g} core-h cannot decide it: the next round on "
            f"{', '.join(targets)} would take ~{hours:.2g} core-h more "
            f"({base['core_hours']:.2g} spent; the same command with a cap of at least "
            f"{base['core_hours'] + hours:.2g} core-h continues)"))
    return Look(**base, target=", ".join(targets), actions=tuple(actions),
                planned_core_hours=hours)


# ---------------------------------------------------------------- the loop
class Stand(StrEnum):
    """Where a sequential study stands (:func:`stand`; the value is the word shown)."""

    STOPPED = "stopped"             # the last look stopped it: only the final report remains
    ROUND_DUE = "round due"         # the round the last look asked for is not handed out yet
    RUNNING = "running"             # a case of the round is held (a live runner, a queued task)
    INCOMPLETE = "incomplete"       # a case of the round is not done and nobody holds it
    LOOK_DUE = "look due"           # every case of the round is done


STOPPED, ROUND_DUE, RUNNING, INCOMPLETE, LOOK_DUE = (
    Stand.STOPPED, Stand.ROUND_DUE, Stand.RUNNING, Stand.INCOMPLETE, Stand.LOOK_DUE)


def stand(rounds: Rounds, handed: int, needs: Eligible, where: Path) -> Stand:
    """Where the sequential study in ``where`` stands, the one decision every executor's
    loop acts on: ``rounds`` (k looks taken), ``handed`` the latest round its executor was
    given (written locally; submitted on a scheduler: the round its jobs name) and
    ``needs`` what each case of that round needs. Stopped by the last look; round k + 1
    due while ``handed`` <= k; else running while a case is held, incomplete while one is
    not done, the look due once all are. A round handed out before the look that asked
    for it is refused (another rounds record was put in place)."""
    k = len(rounds.looks)
    if rounds.stopped:
        return STOPPED
    if handed > k + 1:
        raise ConfigError(f"{where}: the executor's record names round {handed}, the rounds "
                          f"record {k} look(s): round {handed} cannot have been submitted "
                          f"before look {handed - 1}; was the rounds record replaced?")
    if handed <= k:
        return ROUND_DUE
    if any(t.need is HELD for t in needs.tasks):
        return RUNNING
    return INCOMPLETE if needs.not_done else LOOK_DUE


def drive(state: Callable[[], Stand], act: Mapping[Stand, Callable[[], bool]]) -> Stand:
    """The one loop of rounds, for every executor: ask where the study stands (``state``,
    read afresh each turn from the records: :func:`stand`), do what ``act`` does in that
    state, and ask again, until the study stops. An act returns False to end the loop
    there (a round handed to a scheduler that runs it on its own, a case that did not
    finish): the state it ended in is returned, else :data:`STOPPED`. The local loop
    (:func:`until_decided`) and a scheduler's follow-up job
    (:func:`ligwf.pipeline.submit_rounds.keep_going`) differ only in their acts."""
    while (now := state()) != STOPPED:
        if not act[now]():
            return now
    return STOPPED


def until_decided(prepared: Prepared, out: Path, executor: Executor, plan: RoundPlan,
                  run_round: Callable[[StudyRun], bool], show: Callable[[Look, Rounds], None],
                  mesh_cache: Path | None = None, snapshots: bool = True,
                  replace: bool = False) -> Rounds:
    """Run, analyse and judge the study in rounds until it decides (module docstring), its
    cases and analysis on ``executor`` (one that runs them to their end: this machine, or a
    scheduler that waits); ``run_round`` runs the due cases of a round (the CLI's progress
    display), ``show`` prints a look. The loop (:func:`drive`) acts on :func:`stand`: a
    due round is written (:func:`write_round`), a round whose cases are not done is run, a
    due look is taken (:func:`take_look`), until the study stops (then the final report).
    Returns the rounds record; stops early (no look recorded) when a case did not finish
    (the same command resumes it). Another study in ``out`` is refused before the rounds
    record is touched, unless ``replace``."""
    check_own_folder(out, prepared.workflow.name, prepared.workflow.raw,
                     [rc.case.case_id for rc in prepared.rendered], (), replace)
    rounds = start_rounds(out, plan)
    handed = len(rounds.looks)      # each call writes its round first (idempotent)
    identity = None

    def state() -> Stand:
        needs = (eligible(Study.open(out).cases) if handed > len(rounds.looks)
                 else Eligible(()))
        return stand(rounds, handed, needs, out)

    def hand_out() -> bool:
        nonlocal handed, identity
        _, identity = site_engine()                 # refused before anything is written
        write_round(prepared, out, rounds, mesh_cache, replace)
        handed = len(rounds.looks) + 1
        return True

    def look() -> bool:
        nonlocal rounds
        rounds = take_look(out, rounds, executor)
        show(rounds.looks[-1], rounds)
        return True

    def run() -> bool:                              # RUNNING elsewhere, or INCOMPLETE
        return run_round(scheduled(Study.open(out), executor, identity))

    if drive(state, {ROUND_DUE: hand_out, LOOK_DUE: look, RUNNING: run,
                     INCOMPLETE: run}) == STOPPED:
        report_study(out, snapshots=snapshots)
    return rounds


# ---------------------------------------------------------------- the steps of a round
def write_round(prepared: Prepared, out: Path, rounds: Rounds,
                mesh_cache: Path | None = None, replace: bool = False) -> Study:
    """Write the study as its looks left it: the workflow's cases and the replicas the
    rounds added (:func:`added_cases`), then the production extensions
    (:func:`apply_extensions`). Idempotent (an unchanged case is rewritten byte for byte,
    an extension only where it differs); the study read afresh (its cases rescheduled).
    The local loop and a scheduler's follow-up job (:mod:`ligwf.pipeline.submit_rounds`)
    both write a round this way."""
    study = write(added_cases(prepared, rounds), out, mesh_cache, replace)
    apply_extensions(study, rounds)
    return Study.open(out)


def take_look(out: Path, rounds: Rounds, executor: Executor) -> Rounds:
    """Analyse (on ``executor``) and report the study (no snapshots), plan the next look
    from the report's verdict (:func:`plan_look`) and write it into the rounds record
    before anything acts on it; the record with that look."""
    postprocess(out, executor, snapshots=False)
    study = Study.open(out)
    verdict = read_verdict(study.report_dir)
    if verdict is None:
        raise ConfigError(f"{study.report_dir}: the report wrote no verdict (no accept: "
                          "budget?): a sequential study needs one")
    rounds = rounds.with_look(plan_look(verdict, study, rounds, len(rounds.looks) + 1))
    write_rounds(out, rounds)
    return rounds
