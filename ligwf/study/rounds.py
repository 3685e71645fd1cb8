"""The record of a sequential study (``ligwf study --until-decided``): its plan and its looks.

One JSON file in the study folder (:data:`~ligwf.study.layout.ROUNDS_FILE`), written and
read only here. It holds the plan fixed at the first look (at most ``max_looks`` looks,
the family ``alpha``, the core-hour cap) and, per look, the verdict's criteria as they
stood (value, interval, state), the condition the next round works on, what it adds
(production extended on named runs to a named step, or new replicas of a condition) and,
on the last look, why the study stopped.

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
from dataclasses import asdict, dataclass, field
from pathlib import Path

from ligwf.errors import ConfigError
from ligwf.fsio import atomic_write_json, json_safe, try_lock
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
    actions: tuple[dict, ...] = ()
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
                           tuple(x.get("actions", ())),
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


def write_rounds(study_path: Path, rounds: Rounds) -> None:
    """Write the record atomically (a kill leaves the old one or the new one)."""
    rec = {"max_looks": rounds.max_looks, "alpha": rounds.alpha,
           "alpha_per_look": rounds.alpha_per_look, "method": "Bonferroni alpha spending "
           "over max_looks looks (each look at alpha / max_looks), Hsu's conservative "
           "degrees of freedom (min(R1, R2) - 1)",
           "max_core_hours": rounds.max_core_hours, "every_level": rounds.every_level,
           "looks": [json_safe(asdict(x)) for x in rounds.looks]}
    atomic_write_json(Path(study_path) / ROUNDS_FILE, rec)


def rounds_lock(study_path: Path):
    """Try to become the one process that moves the sequential study on (takes its next
    look, submits its next round): a context that yields whether the lock was taken (no
    waiting; released when the block ends or the process dies)."""
    return try_lock(Path(study_path) / ROUNDS_LOCK)
