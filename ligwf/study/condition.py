"""The identities a study compares: the condition and its two arms.

A **condition** is what replicas are pooled over: a sweep group
(:class:`~ligwf.study.group.SweepGroup`, stored as its canonical JSON), a CG level and a
rule. A CG-n condition is compared with the CG1 runs of its own sweep group, its
**reference**; the CG1 conditions are the references themselves. The two sides of that
comparison are the **arms**: CG-n (the condition's own runs) and CG1 (the reference's). A
round of a sequential study adds runs to an arm (:mod:`ligwf.study.rounds`); the analysis
groups cases by condition (:class:`ligwf.analysis.records.conditions.Conditions`); the
verdict and the report name them by :attr:`Condition.name`.

These live with the folder model because a case folder already carries them (its group,
CG level and rule): every stage above reads them from here.
"""

from __future__ import annotations

from dataclasses import dataclass
from enum import Enum

from ligwf.scene.scaling import Rule
from ligwf.study.group import SweepGroup

#: the CG level every other level is compared with
REFERENCE_CG = 1.0


class Arm(str, Enum):
    """One side of a comparison: the CG-n runs of a condition or the CG1 runs it is
    compared with. The values are the words the verdict's records and the rounds record
    use (``round_arm`` names one or both: ``CG-n and CG1``)."""

    CG_N = "CG-n"
    CG1 = "CG1"

    @classmethod
    def of_level(cls, cg: float) -> "Arm":
        """The arm a run of CG level ``cg`` is on."""
        return cls.CG1 if cg == REFERENCE_CG else cls.CG_N

    @classmethod
    def named_in(cls, text: str) -> tuple["Arm", ...]:
        """The arms a criterion's ``round_arm`` / ``decide_arm`` names (``CG-n``, ``CG1``,
        ``CG-n and CG1``; none for empty or other text), in :class:`Arm` order."""
        words = str(text).split(" and ")
        return tuple(arm for arm in cls if arm.value in words)


@dataclass(frozen=True)
class Condition:
    """Cases pooled together: same sweep group (canonical JSON), CG level and rule."""

    group: str
    cg: float
    rule: str

    @classmethod
    def of(cls, case) -> "Condition":
        """The condition of anything with ``group``, ``cg`` and ``rule`` (a case folder,
        a row of a case table)."""
        return cls(case.group, case.cg, case.rule)

    @property
    def is_reference(self) -> bool:
        """A CG1 condition: what the other levels of its group are compared with."""
        return self.cg == REFERENCE_CG

    @property
    def arm(self) -> Arm:
        """The arm this condition's runs are on (CG1 for a reference)."""
        return Arm.of_level(self.cg)

    @property
    def reference(self) -> "Condition":
        """The CG1 condition this one is compared with (itself for a reference)."""
        return Condition(self.group, REFERENCE_CG, Rule.NONE.value)

    def side(self, arm: Arm) -> "Condition":
        """The condition whose runs are ``arm`` of this one's comparison: itself for
        CG-n, its reference for CG1."""
        return self.reference if arm == Arm.CG1 else self

    def covers(self, case) -> bool:
        """Whether ``case`` (with ``group``, ``cg``, ``rule``) is one of this condition's
        runs; a reference covers every CG1 run of its group, whatever rule it names."""
        return (case.group == self.group and case.cg == self.cg
                and (self.is_reference or case.rule == self.rule))

    @property
    def sweep_group(self) -> SweepGroup:
        """The sweep group as a value (:attr:`group` is its canonical JSON, what tables and
        records store; read once per distinct text, :meth:`SweepGroup.parse`)."""
        return SweepGroup.parse(self.group)

    @property
    def name(self) -> str:
        """``cg2-weber``; with a sweep group its readable name (``cg1 cohesionless
        control``, ``cg2-weber process.rotation.rpm=20``: :attr:`SweepGroup.label`)."""
        tag = f"cg{self.cg:g}" + ("" if self.is_reference else f"-{self.rule}")
        return tag if self.group in ("{}", "") else f"{tag} {self.sweep_group.label}"

    @property
    def key(self) -> tuple[str, float, str]:
        """Sort key: group, CG level, rule."""
        return self.group, self.cg, self.rule
