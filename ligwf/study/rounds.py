"""The record of a sequential study (``ligwf study --until-decided``): its plan and its looks.

One JSON file in the study folder (:data:`~ligwf.study.layout.ROUNDS_FILE`), written and
read only here. It holds the plan fixed at the first look (at most ``max_looks`` looks,
the family ``alpha``, the core-hour cap) and, per look, the verdict's criteria as they
stood (value, interval, state), the condition the next round works on, what it adds
(its actions, typed: :class:`ExtendProduction`, production extended on named runs to a
named step, and :class:`AddReplicas`, new replicas of an arm; each writes and reads its
own JSON) and, on the last look, why the study stopped.

Repeated looks are paid for by **Bonferroni alpha spending**: every look tests at
``alpha / max_looks`` (:attr:`Rounds.alpha_per_look`), so the chance that any look of the
study passes or fails a criterion wrongly is at most ``alpha`` whatever the data do
between looks (the union bound; conservative, and it needs no assumption about how much
each round adds), and with Hsu's conservative degrees of freedom (min(R1, R2) - 1 instead
of Welch's: sample sizes chosen from the measured variances made Welch's looks err up to
~7 % on null synthetic studies, ``benchmarks/bench_coverage.py``). The report of a
sequential study decides at that level from its first look on.
"""

from __future__ import annotations

import json
from dataclasses import dataclass, field, fields
from pathlib import Path
from typing import Any, ClassVar, Mapping, Union

from ligwf.errors import ConfigError
from ligwf.fsio import atomic_write_json, json_safe, try_lock
from ligwf.study.condition import Arm, Condition
from ligwf.study.layout import ROUNDS_FILE, ROUNDS_LOCK

#: the family error rate of a study's decisions
FAMILY_ALPHA = 0.05
#: looks a sequential study takes at most unless told otherwise
DEFAULT_LOOKS = 3
#: the kinds of action a round takes
EXTEND, REPLICAS = "extend", "replicas"
#: why a study stopped (a look's ``stop_kind``): it decided, no planned way decides it, its
#: looks are spent, or the next round would pass the core-hour cap (the one a later call
#: with a higher cap continues from)
DECIDED, STUCK, LOOKS_SPENT, CAPPED = "decided", "stuck", "looks spent", "capped"


@dataclass(frozen=True)
class ExtendProduction:
    """A round's longer production on the runs of one arm: ``seconds`` more each, every
    case of ``case_ids`` (in the study's order) continued to its step in ``run_steps``
    (a target step, so applying it again changes nothing)."""

    kind: ClassVar[str] = EXTEND
    arm: Arm
    seconds: float
    case_ids: tuple[str, ...]
    run_steps: Mapping[str, int]

    def to_json(self) -> dict[str, Any]:
        """The action as the rounds record stores it."""
        return {"kind": self.kind, "arm": self.arm.value, "seconds": self.seconds,
                "case_ids": list(self.case_ids), "run_steps": dict(self.run_steps)}

    @classmethod
    def from_json(cls, rec: Mapping[str, Any]) -> "ExtendProduction":
        seconds = rec["seconds"]
        return cls(Arm(rec["arm"]), float("nan") if seconds is None else float(seconds),
                   tuple(str(c) for c in rec["case_ids"]),
                   {str(c): int(n) for c, n in rec["run_steps"].items()})


@dataclass(frozen=True)
class AddReplicas:
    """A round's new replicas of one arm: the runs of ``condition`` (for the CG1 arm, the
    reference condition of its sweep group) numbered ``replicas`` (new case folders with
    new seeds), each with ``each_run_steps`` production steps (as long as the arm's runs,
    extended ones included)."""

    kind: ClassVar[str] = REPLICAS
    condition: Condition
    replicas: tuple[int, ...]
    each_run_steps: int

    @property
    def arm(self) -> Arm:
        return self.condition.arm

    def to_json(self) -> dict[str, Any]:
        """The action as the rounds record stores it (the condition's fields and name)."""
        c = self.condition
        return {"kind": self.kind, "arm": self.arm.value, "group": c.group, "cg": c.cg,
                "rule": c.rule, "replicas": list(self.replicas),
                "each_run_steps": self.each_run_steps, "condition": c.name}

    @classmethod
    def from_json(cls, rec: Mapping[str, Any]) -> "AddReplicas":
        return cls(Condition(str(rec["group"]), float(rec["cg"]), str(rec["rule"])),
                   tuple(int(r) for r in rec["replicas"]), int(rec["each_run_steps"]))


#: what a round does: longer production on an arm's runs, or new replicas of an arm
Action = Union[ExtendProduction, AddReplicas]
_ACTIONS: dict[str, type] = {EXTEND: ExtendProduction, REPLICAS: AddReplicas}


def read_action(rec: Mapping[str, Any]) -> Action:
    """An action as the rounds record stores it (:meth:`ExtendProduction.to_json`,
    :meth:`AddReplicas.to_json`); KeyError for an unknown kind."""
    return _ACTIONS[rec["kind"]].from_json(rec)


@dataclass(frozen=True)
class Look:
    """One look: its number (1-based), the level it decided at, the core-hours the study's
    runs had cost by then (from the manifests), the criteria of every condition
    (``{condition, criterion, label, unit, state, value, lo, hi, budget}``), the condition
    the next round works on, its actions and their planned core-hours, and why the study
    stopped here (empty: it goes on)."""

    number: int
    alpha: float
    core_hours: float
    criteria: tuple[dict, ...] = ()
    target: str = ""
    actions: tuple[Action, ...] = ()
    planned_core_hours: float = 0.0
    stop: str = ""
    stop_kind: str = ""


@dataclass(frozen=True)
class Rounds:
    """A sequential study's plan and its looks (the default: one look at ``alpha``).
    ``every_level``: the rounds work on the undecided criteria of every CG level (a
    ladder: what each level is shown to stay within), not only on the cheapest level that
    can still pass."""

    max_looks: int = 1
    alpha: float = FAMILY_ALPHA
    max_core_hours: float | None = None
    looks: tuple[Look, ...] = field(default_factory=tuple)
    every_level: bool = False

    @property
    def alpha_per_look(self) -> float:
        """The level every look tests at (Bonferroni spending over ``max_looks``)."""
        return self.alpha / self.max_looks

    @property
    def stopped(self) -> bool:
        return bool(self.looks) and bool(self.looks[-1].stop)

    def with_look(self, look: Look) -> "Rounds":
        """The record with ``look`` added (or replacing a look of the same number)."""
        kept = tuple(x for x in self.looks if x.number < look.number)
        return Rounds(self.max_looks, self.alpha, self.max_core_hours, kept + (look,),
                      self.every_level)


#: how a record written before ``stop_kind`` existed words each kind of stop
_STOP_WORDS = (("decided", DECIDED), ("no planned way", STUCK), ("the cap of", CAPPED))


def _legacy_kind(stop: str) -> str:
    """The kind of a stop recorded before looks stored it, from its words (empty for a
    look that did not stop)."""
    if not stop:
        return ""
    for words, kind in _STOP_WORDS:
        if stop.startswith(words):
            return kind
    return LOOKS_SPENT if "looks are spent" in stop else ""


def read_rounds(study_path: Path) -> Rounds:
    """The record of the study folder ``study_path`` (the one-look default when it has
    none); ConfigError when it is unreadable."""
    path = Path(study_path) / ROUNDS_FILE
    try:
        rec = json.loads(path.read_text())
    except FileNotFoundError:
        return Rounds()
    except (OSError, ValueError) as exc:
        raise ConfigError(f"{path}: unreadable record of the study's rounds ({exc})") from None
    try:
        looks = tuple(Look(int(x["number"]), float(x["alpha"]), float(x["core_hours"]),
                           tuple(x.get("criteria", ())), str(x.get("target", "")),
                           tuple(read_action(a) for a in x.get("actions", ())),
                           float(x.get("planned_core_hours") or 0.0), str(x.get("stop", "")),
                           str(x.get("stop_kind", "")) or _legacy_kind(str(x.get("stop", ""))))
                      for x in rec.get("looks", ()))
        cap = rec.get("max_core_hours")
        return Rounds(int(rec["max_looks"]), float(rec["alpha"]),
                      None if cap is None else float(cap), looks,
                      bool(rec.get("every_level", False)))
    except (KeyError, TypeError, ValueError) as exc:
        raise ConfigError(f"{path}: unreadable record of the study's rounds "
                          f"({type(exc).__name__}: {exc})") from None


def _look_json(look: Look) -> dict[str, Any]:
    """A look as the record stores it (its actions through their own ``to_json``)."""
    rec = {f.name: getattr(look, f.name) for f in fields(look)}
    rec["actions"] = [a.to_json() for a in look.actions]
    return json_safe(rec)


def write_rounds(study_path: Path, rounds: Rounds) -> None:
    """Write the record atomically (a kill leaves the old one or the new one)."""
    rec = {"max_looks": rounds.max_looks, "alpha": rounds.alpha,
           "alpha_per_look": rounds.alpha_per_look, "method": "Bonferroni alpha spending "
           "over max_looks looks (each look at alpha / max_looks), Hsu's conservative "
           "degrees of freedom (min(R1, R2) - 1)",
           "max_core_hours": rounds.max_core_hours, "every_level": rounds.every_level,
           "looks": [_look_json(x) for x in rounds.looks]}
    atomic_write_json(Path(study_path) / ROUNDS_FILE, rec)


def rounds_lock(study_path: Path):
    """Try to become the one process that moves the sequential study on (takes its next
    look, submits its next round): a context that yields whether the lock was taken (no
    waiting; released when the block ends or the process dies)."""
    return try_lock(Path(study_path) / ROUNDS_LOCK)
