"""A committed results folder (ligwf.api.results_folder): its README is rendered from its
committed tables, ``check`` names the command that remakes a stale one, and a study's
report tables are read through open_study before their bytes are copied. The report
tables are the committed demo's (docs/results/demo), placed in a rendered study."""

from __future__ import annotations

import shutil

import pandas as pd
import pytest

from helpers import ROOT
from ligwf.api import MissingOutput
from ligwf.api.results_folder import (ResultsFolder, check_all, csv_text, from_template,
                                      number, results_command, runs_rows, verdict_rows)
from ligwf.cli.main import main
from ligwf.errors import ConfigError
from ligwf.study import layout

DEMO = ROOT / "docs" / "results" / "demo"
TINY = ROOT / "tests" / "workflows" / "tiny_study.yaml"


def count_rows(folder: ResultsFolder) -> str:
    return f"{len(folder.table('t.csv'))} rows\n"


@pytest.fixture
def folder(tmp_path):
    out = tmp_path / "results"
    out.mkdir()
    (out / "t.csv").write_text(csv_text(pd.DataFrame({"x": [1.0, 2.0 / 3.0]})))
    return ResultsFolder(out, count_rows, "scripts/make_t.py STUDY")


@pytest.fixture(scope="module")
def study(tmp_path_factory):
    """A rendered study whose report folder holds the committed demo's report files."""
    out = tmp_path_factory.mktemp("results_folder") / "study"
    assert main(["render", str(TINY), "--out", str(out), "--set", "sweep.rules=[weber]"]) == 0
    report = out / layout.REPORT_DIR
    report.mkdir()
    for name in (layout.VERDICT_TABLE, layout.CASES_REPORT, layout.SUMMARY_REPORT):
        shutil.copyfile(DEMO / name, report / name)
    return out


def test_number_and_csv_text():
    assert (number(0.123456), number(2.0, 4), number(float("nan")), number("x")) == (
        "0.123", "2", "–", "–")
    assert csv_text(pd.DataFrame({"a": [1 / 3]})) == "a\n0.333333\n"


def test_written_readme_checks_and_a_changed_table_does_not(folder):
    assert folder.check()                      # no README yet
    assert folder.write() == "2 rows\n" == folder.readme.read_text()
    assert folder.check() == [] and check_all([folder]) == []
    (folder.path / "t.csv").write_text("x\n1\n")
    [problem] = folder.check()
    assert "differs from its tables" in problem and "scripts/make_t.py STUDY" in problem


def test_a_stale_table_is_one_line_not_a_traceback(folder):
    """A committed table that lost a column its README reads (or that does not parse) is
    named in one line with the command that remakes it."""
    def by_column(f: ResultsFolder) -> str:
        return f"{f.table('t.csv').x.sum():g}\n"

    stale = ResultsFolder(folder.path, by_column, "scripts/make_t.py STUDY", doubled)
    stale.write()
    (folder.path / "t.csv").write_text("y\n1\n")          # the column x is gone
    problems = stale.check()
    assert any("cannot be written from the committed tables" in p for p in problems)
    assert all("scripts/make_t.py STUDY" in p for p in problems)
    (folder.path / "t.csv").write_text('x\n"unterminated\n')
    assert all("scripts/make_t.py STUDY" in p for p in stale.check())


def doubled(folder: ResultsFolder) -> dict[str, str]:
    return {"d.csv": csv_text(folder.table("t.csv") * 2)}


def test_a_template_is_filled_from_the_tables_and_checked(folder, tmp_path):
    """Hand-written prose as a template: its fields come from the committed table, a
    changed table makes the README stale, and a field named but not given (or given and
    never named) is refused by name."""
    template = tmp_path / "readme.md"
    template.write_text("The {n} rows sum to {total} (a set: {{x}}).\n")
    def sums(f):
        return {"n": len(f.table("t.csv")), "total": number(f.table("t.csv")["x"].sum())}
    filled = ResultsFolder(folder.path, from_template(template, sums), "scripts/make_t.py")
    assert filled.write() == "The 2 rows sum to 1.67 (a set: {x}).\n"
    assert filled.check() == []
    (folder.path / "t.csv").write_text(csv_text(pd.DataFrame({"x": [1.0]})))
    assert filled.check() == [f"{filled.readme} differs from its tables: run scripts/make_t.py"]
    template.write_text("The {n} rows sum to {sum}.\n")
    with pytest.raises(ConfigError, match=r"named but not given: \['sum'\]; given but not "
                                          r"named: \['total'\]"):
        filled.text()


def test_a_derived_table_is_written_and_checked_byte_for_byte(folder):
    derived = ResultsFolder(folder.path, None, "scripts/make_d.py", doubled)
    assert derived.text() is None and derived.write() == "wrote d.csv"
    assert (folder.path / "d.csv").read_text() == "x\n2\n1.33333\n"
    assert not folder.readme.exists() and derived.check() == []
    (folder.path / "t.csv").write_text("x\n1\n")
    [problem] = derived.check()
    assert "d.csv differs" in problem and "scripts/make_d.py" in problem


def test_the_command_checks_every_folder_and_writes_what_make_fills(folder, capsys):
    def make(args):
        folder.copy(args.study, "t.csv")
        return folder

    assert results_command("doc", [folder], make, ["--check"]) == 1
    source = folder.path.parent / "run"
    source.mkdir()
    (source / "t.csv").write_text("x\n1\n2\n3\n")
    assert results_command("doc", [folder], make, [str(source)]) == 0
    assert "3 rows" in capsys.readouterr().out
    assert results_command("doc", [folder], make, ["--check"]) == 0


def test_copy_report_copies_the_study_tables_byte_for_byte(study, tmp_path):
    target = ResultsFolder(tmp_path / "out", count_rows, "")
    names = (layout.VERDICT_TABLE, layout.CASES_REPORT, layout.SUMMARY_REPORT)
    target.copy_report(study, names)
    for name in names:
        assert (target.path / name).read_bytes() == (DEMO / name).read_bytes()


def test_copy_report_refuses_a_table_ligwf_did_not_write(study, tmp_path):
    broken = tmp_path / "study"
    shutil.copytree(study, broken)
    path = broken / layout.REPORT_DIR / layout.VERDICT_TABLE
    pd.read_csv(path).rename(columns={"criterion": "name"}).to_csv(path, index=False)
    target = ResultsFolder(tmp_path / "out", count_rows, "")
    with pytest.raises(MissingOutput, match="run `ligwf report"):
        target.copy_report(broken, [layout.VERDICT_TABLE])
    with pytest.raises(ConfigError, match="missing; run `ligwf report"):
        target.copy_report(study, [layout.HTML_REPORT])


def test_rows_of_the_runs_and_verdict_tables_are_the_committed_readme_lines():
    readme = (DEMO / "README.md").read_text().splitlines()
    cases = pd.read_csv(DEMO / layout.CASES_REPORT)
    rows = runs_rows(cases, [("angle_of_repose", ".2f"), ("angle_of_repose_std", ".2f"),
                             ("rigid_frame_share", ".2f"), ("wall_seconds", ".0f")])
    assert len(rows) == cases.groupby(["cg", "rule"]).ngroups and set(rows) <= set(readme)
    verdict = pd.read_csv(DEMO / layout.VERDICT_TABLE)
    assert set(verdict_rows(verdict)) <= set(readme) and len(verdict_rows(verdict)) == len(verdict)
