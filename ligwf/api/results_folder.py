"""A committed results folder: a study's tables beside a README written from them.

``docs/results/NAME/`` holds the tables a finding rests on (copied from a study's report,
or measured by a script) and a README whose every number is read from those tables. A
results script declares one :class:`ResultsFolder` -- where it is, which function renders
its README from its tables, which command remakes it -- and the folder does the rest:

* :meth:`ResultsFolder.copy_report` copies a study's report files into it, reading each
  table first through :func:`ligwf.api.open_study` (a table ligwf did not write, or one that
  is missing, is refused with the command that writes it) and then copying its bytes, so
  the committed table is the study's file exactly;
* a table the folder derives from committed tables (its own, or another folder's: a claim
  computed from copied case tables, a fit over several studies) is declared as
  ``derived``: :meth:`ResultsFolder.write` writes it, :meth:`ResultsFolder.check`
  recomputes it and compares the text;
* :meth:`ResultsFolder.write` renders the README from the committed tables (not from the
  study folder: what is committed is what is checked) and writes it;
* :meth:`ResultsFolder.check` renders it again and says how it differs from the committed
  one: a sentence cannot drift from its table. The committed-results tests run it, on the
  committed tables alone (the run folders are not committed). A README still written by
  hand (``render`` None) is checked by its folder's test, number by number.

Table names come from :mod:`ligwf.study.layout` (a copied report table keeps its name);
a table a script measures itself is named by that script. :func:`number` and
:func:`csv_text` are how a README prints a value and how a measured table is written.
:func:`from_template` renders a README whose prose was written by hand: the prose is the
template, each number a committed table holds one of its fields.
"""

from __future__ import annotations

import argparse
import math
import shutil
import string
import sys
from dataclasses import dataclass
from pathlib import Path
from typing import Callable, Iterable, Mapping, Sequence

import pandas as pd

from ligwf.api.results import open_study
from ligwf.api.tables import TABLES
from ligwf.errors import ConfigError
from ligwf.study import layout


def number(value, digits: int = 3) -> str:
    """A table value as a README prints it: ``digits`` significant digits, ``–`` for nan or
    what is not a number."""
    try:
        value = float(value)
    except (TypeError, ValueError):
        return "–"
    return f"{value:.{digits}g}" if math.isfinite(value) else "–"


def csv_text(table: pd.DataFrame) -> str:
    """A table a results script measured, as committed: no index, numbers to 6 significant
    digits."""
    return table.to_csv(index=False, float_format="%.6g")


#: what reading a stale or damaged committed table raises (a column gone, a bad CSV)
_UNREADABLE = (OSError, KeyError, AttributeError, ValueError, pd.errors.ParserError)


@dataclass(frozen=True)
class ResultsFolder:
    """One committed results folder: ``path``; ``render(folder) -> text``, its README from
    its committed tables (None: a README written by hand, whose numbers the folder's test
    reads from the tables); ``remake``, the command that writes it again (named when
    :meth:`check` finds it stale); ``derived(folder) -> {name: text}``, the tables it
    recomputes from committed tables (its own or other folders'), written and checked byte
    for byte."""

    path: Path
    render: Callable[["ResultsFolder"], str] | None
    remake: str
    derived: Callable[["ResultsFolder"], dict[str, str]] | None = None

    @property
    def readme(self) -> Path:
        return self.path / layout.RESULTS_README

    def table(self, name: str) -> pd.DataFrame:
        """The committed table ``name`` as its CSV reads (the README's source)."""
        return pd.read_csv(self.path / name)

    def optional_table(self, name: str) -> pd.DataFrame | None:
        """:meth:`table`, or None when the folder does not have it."""
        return self.table(name) if self.has(name) else None

    def has(self, name: str) -> bool:
        return (self.path / name).is_file()

    def text(self) -> str | None:
        """The README its committed tables give (None: written by hand)."""
        return None if self.render is None else self.render(self)

    def check(self) -> list[str]:
        """What differs from what the committed tables give, one line each naming the
        command that remakes it: each derived table, then the README (empty: nothing)."""
        problems = []
        try:
            derived = {} if self.derived is None else self.derived(self)
        except _UNREADABLE as exc:
            return [f"{self.path}: its committed tables cannot be read ({type(exc).__name__}: "
                    f"{exc}): run {self.remake}"]
        for name, text in derived.items():
            if not self.has(name) or (self.path / name).read_text() != text:
                problems.append(f"{self.path / name} differs from what the committed tables "
                                f"give: run {self.remake}")
        try:
            body = self.text()
        except _UNREADABLE as exc:
            # a stale committed table (a column the README reads is missing): one line
            return problems + [f"{self.readme} cannot be written from the committed tables "
                               f"({type(exc).__name__}: {exc}): run {self.remake}"]
        if body is not None and (not self.readme.is_file() or self.readme.read_text() != body):
            problems.append(f"{self.readme} differs from its tables: run {self.remake}")
        return problems

    def write(self) -> str:
        """Write the derived tables, then the README rendered from the committed tables;
        return what was written (the README's text, or the derived tables' names)."""
        self.path.mkdir(parents=True, exist_ok=True)
        derived = {} if self.derived is None else self.derived(self)
        for name, text in derived.items():
            (self.path / name).write_text(text)
        body = self.text()
        if body is None:
            return "wrote " + ", ".join(sorted(derived))
        self.readme.write_text(body)
        return body

    def copy_report(self, study: Path, names: Iterable[str], *, figures: bool = False,
                    prefix: str = "") -> None:
        """Copy the report files ``names`` (:mod:`ligwf.study.layout` names) of the study
        folder ``study`` here, byte for byte, as ``prefix + name`` (a folder holding several
        studies' reports); with ``figures`` its figures folder too (replacing the one
        here). A report table is first read through :func:`~ligwf.api.open_study`
        (MissingOutput, naming the command that writes it, when it is missing or is not
        the table ligwf writes)."""
        results = open_study(study)
        tables = {spec.file: spec.attribute for spec in TABLES
                  if spec.folder == layout.REPORT_DIR}
        self.path.mkdir(parents=True, exist_ok=True)
        for name in names:
            if name in tables:
                results.table(tables[name])
            source = results.report_dir / name
            if not source.is_file():
                raise ConfigError(f"{source}: missing; run `ligwf report {study}`")
            shutil.copyfile(source, self.path / (prefix + name))
        if figures:
            target = self.path / layout.FIGURES_DIR
            if target.exists():
                shutil.rmtree(target)
            shutil.copytree(results.report_dir / layout.FIGURES_DIR, target)

    def copy(self, source: Path, name: str, as_name: str | None = None) -> None:
        """Copy the file ``source``/``name`` here (as ``as_name``), byte for byte: a record a
        study keeps beside its report (``layout.ROUNDS_FILE``) or a file a run left."""
        self.path.mkdir(parents=True, exist_ok=True)
        shutil.copyfile(source / name, self.path / (as_name or name))


def from_template(template: Path, fields: Callable[["ResultsFolder"], Mapping[str, object]]
                  ) -> Callable[["ResultsFolder"], str]:
    """A folder's ``render``: the text of ``template`` (``{name}`` fields, ``{{`` for a
    brace) filled with ``fields(folder)``, the values read from the folder's committed
    tables. Both sides must agree: a field the template names and ``fields`` does not give,
    or one given and never named (a number read for nothing), is a ConfigError naming it."""
    def render(folder: "ResultsFolder") -> str:
        text = template.read_text()
        named = {name for _, name, _, _ in string.Formatter().parse(text) if name}
        values = dict(fields(folder))
        if named != set(values):
            raise ConfigError(f"{template}: fields named but not given: "
                              f"{sorted(named - set(values)) or 'none'}; given but not named: "
                              f"{sorted(set(values) - named) or 'none'}")
        return text.format_map(values)
    return render


def check_all(folders: Iterable[ResultsFolder]) -> list[str]:
    """The problems of ``folders`` (:meth:`ResultsFolder.check`), one line each."""
    return [problem for folder in folders for problem in folder.check()]


def results_command(doc: str, folders: Sequence[ResultsFolder],
                    make: Callable[[argparse.Namespace], ResultsFolder | None],
                    argv: Sequence[str] | None = None,
                    arguments: Callable[[argparse.ArgumentParser], None] | None = None) -> int:
    """The command line of a results script (its docstring ``doc``): ``STUDY [options]``
    fills a folder (``make(args)``: copy or measure its tables, return the folder; None for
    a step that writes no folder) and writes its derived tables and README; ``--check``
    recomputes them for every folder of ``folders`` from the committed tables and fails (1,
    one line each) where one differs.
    ``arguments`` adds the script's own options; ``make`` may call ``args.error(message)``
    for a usage error."""
    ap = argparse.ArgumentParser(description=doc.splitlines()[0])
    ap.add_argument("study", nargs="?", type=Path, help="the study (or run) folder")
    ap.add_argument("--check", action="store_true",
                    help="only check that each committed README and derived table is what "
                         "the committed tables give")
    if arguments is not None:
        arguments(ap)
    args = ap.parse_args(argv)
    if args.check:
        problems = check_all(folders)
        for problem in problems:
            print(problem, file=sys.stderr)
        return 1 if problems else 0
    args.error = ap.error
    folder = make(args)
    if folder is not None:
        print(folder.write())
    return 0


def runs_rows(cases: pd.DataFrame, columns: Sequence[tuple[str, str]]) -> list[str]:
    """The runs of a study's cases table as README table rows, one per CG level and rule:
    ``| cgN-rule | runs | particles | ... |`` with, per ``(column, format)``, the column's
    value of every run in that format."""
    return [f"| cg{cg:g}-{rule} | {len(sub)} | {int(sub['particles'].iloc[0]):,} | "
            + " | ".join(", ".join(format(v, spec) for v in sub[column])
                         for column, spec in columns) + " |"
            for (cg, rule), sub in cases.groupby(["cg", "rule"], sort=True)]


def verdict_rows(verdict: pd.DataFrame) -> list[str]:
    """A study's verdict table as README table rows: condition, speedup (core-s), the
    condition's state, criterion, its state, value [lo, hi], shown within, budget (with the
    criterion's unit)."""
    rows = []
    for _, r in verdict.iterrows():
        unit = f" {r['unit']}" if isinstance(r["unit"], str) and r["unit"] else ""
        rows.append(f"| {r['condition']} | {number(r['speedup_core'])} | "
                    f"{r['condition_state']} | {r['label']} | {r['state']} | "
                    f"{number(r['value'])} [{number(r['lo'])}, {number(r['hi'])}]{unit} | "
                    f"{number(r['shown_within'])}{unit} | {number(r['budget'])}{unit} |")
    return rows
