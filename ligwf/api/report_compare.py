"""Two reports of the same runs side by side, as a results folder words them.

A committed results folder often keeps a study's report beside a second one of the same
runs: re-reported with today's planner, re-analysed with today's steady window, or the same
seeds run again. These functions say what changed: how many flow criteria each decides
(:func:`decided`), the verdict rows whose ``column`` differs (:func:`changed`), the runs both
have and whether a value repeats exactly (:func:`repeated_runs`); :func:`wall_minutes` reads
the wall time of a command timed by ``/usr/bin/time -v``. Tables in, tables out.
"""

from __future__ import annotations

import re
from typing import Iterable

import pandas as pd

#: the verdict states that decide a criterion
DECIDED = ("pass", "fail")


def decided(verdict: pd.DataFrame, criteria: Iterable[str]) -> tuple[int, int]:
    """(rows of ``verdict`` on ``criteria`` that pass or fail, rows on ``criteria``)."""
    rows = verdict[verdict["criterion"].isin(list(criteria))]
    return int(rows["state"].isin(DECIDED).sum()), len(rows)


def beside(verdict: pd.DataFrame, other: pd.DataFrame) -> pd.DataFrame:
    """``verdict``'s rows with the same condition and criterion of ``other`` beside them
    (its columns suffixed ``_new``)."""
    return verdict.merge(other, on=["condition", "criterion"], suffixes=("", "_new"))


def changed(verdict: pd.DataFrame, other: pd.DataFrame, column: str) -> pd.DataFrame:
    """The rows of :func:`beside` whose ``column`` differs between the two verdicts (a
    missing value counts as empty text)."""
    both = beside(verdict, other)
    return both[both[column].fillna("") != both[column + "_new"].fillna("")]


def repeated_runs(cases: pd.DataFrame, then: pd.DataFrame, column: str) -> pd.DataFrame:
    """The runs (CG level, rule, replica) both cases tables have, ``then``'s columns
    suffixed ``_then``, and ``same``: whether ``column`` is equal to every digit stored."""
    both = cases.merge(then, on=["cg", "rule", "replica"], suffixes=("", "_then"))
    return both.assign(same=both[column] == both[column + "_then"])


_ELAPSED = re.compile(r"Elapsed \(wall clock\) time \(h:mm:ss or m:ss\): ([\d:.]+)")


def wall_minutes(text: str) -> float:
    """Minutes of wall time in a ``/usr/bin/time -v`` report (its ``Elapsed`` line);
    ValueError when it has none."""
    found = _ELAPSED.search(text)
    if found is None:
        raise ValueError("no 'Elapsed (wall clock) time' line")
    seconds = 0.0
    for part in found.group(1).split(":"):
        seconds = seconds * 60 + float(part)
    return seconds / 60
