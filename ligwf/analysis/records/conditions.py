"""The conditions of a set of cases and their CG1 references: one grouping for the analysis
and the report.

A condition (:class:`ligwf.study.condition.Condition`) is what replicas are pooled over: a
sweep group, a CG level and a rule. A CG-n condition is compared with the CG1 cases of its
own sweep group (its reference); the CG1 conditions are the references themselves (their
errors against CG1 are the noise floor). :class:`Conditions` holds the conditions of a
set of cases and answers "which condition is this case in" and "which cases is it
compared with" -- the GSD, pooling, kinetics and sensitivity stages and the report's
errors, intervals and noise floors all ask it instead of testing ``cg == 1`` themselves.
"""

from __future__ import annotations

from dataclasses import dataclass, field
from typing import Iterable, Protocol

from ligwf.study.condition import Condition


class CaseLike(Protocol):
    """What a condition needs of a case (:class:`ligwf.study.case.CaseFolder` has it)."""

    case_id: str
    cg: float
    rule: str
    replica: int
    group: str


@dataclass(frozen=True)
class Conditions:
    """The conditions of a set of cases: each with its cases (ids, in the given order)."""

    cases: dict[Condition, tuple[str, ...]]
    _of_case: dict[str, Condition] = field(default_factory=dict, repr=False, compare=False)

    @classmethod
    def of(cls, cases: Iterable) -> "Conditions":
        """From objects with ``case_id``, ``group``, ``cg``, ``rule`` (cases, or the rows of
        a case table via ``itertuples()``)."""
        cases_of: dict[Condition, list[str]] = {}
        of_case: dict[str, Condition] = {}
        for c in cases:
            cond = Condition.of(c)
            cases_of.setdefault(cond, []).append(c.case_id)
            of_case[c.case_id] = cond
        return cls({k: tuple(v) for k, v in cases_of.items()}, of_case)

    def sorted(self) -> list[Condition]:
        """The conditions by group, CG level, rule."""
        return sorted(self.cases, key=lambda c: c.key)

    def groups(self) -> list[str]:
        """The sweep groups, sorted."""
        return sorted({c.group for c in self.cases})

    def condition(self, case_id: str) -> Condition:
        return self._of_case[case_id]

    def references(self, group: str) -> list[Condition]:
        """The CG1 conditions of a sweep group (in the order first seen)."""
        return [c for c in self.cases if c.group == group and c.is_reference]

    def reference_cases(self, group: str) -> list[str]:
        """The ids of the CG1 cases the conditions of a sweep group are compared with."""
        return [cid for ref in self.references(group) for cid in self.cases[ref]]

    def first_reference_case(self) -> str | None:
        """The first CG1 case in the given order (None without one)."""
        return next((cid for cid, c in self._of_case.items() if c.is_reference), None)
