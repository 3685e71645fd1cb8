"""The sweep group: which swept scene values a case shares with the CG1 cases it is compared
with, as one value type instead of a JSON string re-parsed where it is read.

A study stores a group as canonical JSON (``{"process.rotation.rpm": 20}``, ``{}`` when
nothing is swept; a control twin's group adds ``"control": "cohesionless"``): that text is
what tables and records carry (:attr:`SweepGroup.text`), so their bytes do not change.
:meth:`SweepGroup.parse` reads it back (text that is no group record stays a group of
nothing but its text: its :attr:`label` is that text); the label, the control kind and the
wet group a control twin is compared with are properties of the value.
"""

from __future__ import annotations

import json
from functools import lru_cache
from dataclasses import dataclass
from types import MappingProxyType
from typing import Any, Mapping

from ligwf.scene.workflow import CONTROL_KEY

#: the readable name of a group with no swept scene value
ALL_CASES = "all cases"


@dataclass(frozen=True)
class SweepGroup:
    """One sweep group: its swept values (read-only) and, for a text that was no group
    record, that text (``raw``)."""

    values: Mapping[str, Any]
    raw: str | None = None

    @classmethod
    def of(cls, varied: Mapping[str, Any]) -> "SweepGroup":
        return cls(MappingProxyType(dict(varied)))

    @classmethod
    def parse(cls, text: Any) -> "SweepGroup":
        """The group a table or record holds (its canonical JSON), read once per distinct
        text: every stage that meets a group's text gets the same read-only value."""
        return _parsed(str(text))

    @property
    def text(self) -> str:
        """The canonical JSON a study stores (the text it was parsed from, when it was no
        group record)."""
        return self.raw if self.raw is not None else json.dumps(dict(self.values),
                                                                sort_keys=True)

    @property
    def control(self) -> str | None:
        """The control kind of a control twin's group (``cohesionless``, ...), else None."""
        value = self.values.get(CONTROL_KEY)
        return None if value is None else str(value)

    @property
    def wet(self) -> "SweepGroup":
        """The group without its control key: the wet cases a control twin is compared
        with."""
        return SweepGroup.of({k: v for k, v in self.values.items() if k != CONTROL_KEY})

    @property
    def label(self) -> str:
        """The group as a reader names it: ``all cases`` (nothing swept), the swept values
        as ``key=value``, a control twin's as ``cohesionless control, key=value``."""
        if self.raw is not None:
            return self.raw
        parts = [f"{key}={value:g}" if isinstance(value, float) else f"{key}={value}"
                 for key, value in self.values.items() if key != CONTROL_KEY]
        if self.control is not None:
            return ", ".join([f"{self.control} control", *parts])
        return ", ".join(parts) or ALL_CASES


@lru_cache(maxsize=4096)
def _parsed(text: str) -> SweepGroup:
    try:
        varied = json.loads(text)
    except ValueError:
        return SweepGroup(MappingProxyType({}), text)
    if not isinstance(varied, dict):
        return SweepGroup(MappingProxyType({}), text)
    return SweepGroup.of(varied)
