"""ligwf.api / ``ligwf.open_study``: every table of a real reported study read and typed,
missing outputs as one line naming the command, the public names.

The real study is tests/apistudy.py's tiny ``ligwf study`` (engine-marked); the refusals
use a study that is only rendered (no engine) and hand-made analysis records.
"""

from __future__ import annotations

import ast
import json
import os
import re
import shutil
import subprocess
import sys

import numpy as np
import pandas as pd
import pytest

import ligwf
from apistudy import api_study
from helpers import ROOT
from ligwf.api import TABLES, MissingOutput
from ligwf.analysis.records.fields import CaseFields, FieldGrid
from ligwf.api.fields import fields_table, plot_field
from ligwf.api.tables import is_text_column, read_table, typed
from ligwf.cli.main import main
from ligwf.errors import ConfigError, LigwfError
from ligwf.study import layout

TINY = ROOT / "tests" / "workflows" / "tiny_study.yaml"


@pytest.fixture(scope="module")
def reported(engine, tmp_path_factory):
    return api_study(engine, tmp_path_factory)


@pytest.fixture(scope="module")
def rendered(tmp_path_factory):
    """A rendered study: no engine run, no analysis, no report."""
    out = tmp_path_factory.mktemp("rendered") / "study"
    assert main(["render", str(TINY), "--out", str(out), "--set", "sweep.rules=[weber]"]) == 0
    return out


# ---------------------------------------------------------------- a real study
@pytest.mark.engine
@pytest.mark.mpi
def test_every_table_reads_with_its_rows(reported):
    s = ligwf.open_study(reported)
    assert all(s.available().values()), s.available()
    for spec in TABLES:
        table = s.table(spec.attribute)
        # one CG-n level: no rule to extrapolate CG1 from; no placed liquid: nothing spreads;
        # those tables have their columns only
        assert len(table) > 0 or spec.attribute in ("extrapolation", "spreading"), \
            spec.attribute
        raw = (pd.read_parquet if spec.file.endswith("parquet") else pd.read_csv)(
            reported / spec.folder / spec.file)
        assert list(table.columns) == list(raw.columns) and len(table) == len(raw)
        for col in raw.columns:   # same values as the file, numbers as numbers
            if pd.api.types.is_numeric_dtype(table[col]) and not is_text_column(col):
                assert np.allclose(table[col].to_numpy(float), raw[col].to_numpy(float),
                                   equal_nan=True), (spec.attribute, col)
    assert sorted(s.cases["case_id"]) == sorted(s.case_ids)
    assert set(s.conditions["cg"]) == {1.0, 2.0}
    verdict = s.verdict
    assert set(verdict["state"]) <= {"pass", "fail", "undecided", "not assessed", "not measured"}
    assert verdict["cheapest"].dtype == "boolean" and set(verdict["condition"]) == {"cg2-weber", "cg2-bond"}
    groups = s.verdict_result.groups
    assert groups and all(g.sentence for g in groups)
    assert s.cases is not s.cases                          # a copy each time
    cases = s.cases
    cases["cg"] = -1
    assert (s.cases["cg"] > 0).all()


@pytest.mark.engine
@pytest.mark.mpi
def test_dtypes_are_typed_and_one_per_column_name(reported):
    s = ligwf.open_study(reported)
    seen: dict[str, str] = {}
    for name, table in {**s.tables(), "profiles": s.profiles}.items():
        for col, dtype in table.dtypes.items():
            assert dtype != object, f"{name}.{col} is object"
            if is_text_column(col):
                assert dtype == "string", f"{name}.{col}: {dtype}"
            else:   # a text column the API does not name is still text, never object
                assert (pd.api.types.is_numeric_dtype(dtype) or dtype in ("boolean", "string")), \
                    f"{name}.{col}: {dtype}"
            if col in seen and name != "profiles":
                kind = lambda d: "float" if str(d).startswith(("float", "int")) else str(d)
                assert kind(dtype) == kind(seen[col]), f"{col}: {dtype} here, {seen[col]} before"
            seen.setdefault(col, dtype)
    assert s.frames["reason"].dtype == "string"              # all-missing in a clean study
    assert s.conditions["speedup_core"].dtype == "float64"
    assert s.conditions["angle_error_vs_floor"].dtype == "string"


@pytest.mark.engine
@pytest.mark.mpi
def test_every_column_of_every_table_is_described_by_the_data_dictionary(reported):
    s = ligwf.open_study(reported)
    for name, table in s.tables().items():
        d = s.describe(name)
        assert list(d["column"]) == list(table.columns)
        assert list(d["dtype"]) == [str(t) for t in table.dtypes]
        undocumented = d.loc[d["meaning"].isna() | (d["meaning"] == ""), "column"].tolist()
        assert not undocumented, (name, undocumented)
    speed = s.describe("conditions").set_index("column").loc["speedup_core"]
    assert speed["label"] and "CG1" in speed["meaning"]


@pytest.mark.engine
@pytest.mark.mpi
def test_settings_paths_profiles_and_flow_record(reported):
    s = ligwf.open_study(reported)
    s.check()                                   # analysis and report match the study
    assert s.name == "tiny-study" and s.settings.bootstrap == 50
    assert s.workflow["sweep"]["rules"] == ["weber", "bond"]
    assert s.accept.angle_deg > 0                  # the verdict's budget (defaults here)
    assert s.summary.is_file() and s.html.is_file() and s.report_dir == reported / "report"
    assert set(s.paraview) == set(s.cases["case_id"])
    assert all(p.suffix == ".pvd" and p.is_file() for p in s.paraview.values())
    assert layout.FIGURE_ERROR_VS_RUNTIME in s.figures
    prof = s.profiles
    assert set(prof["case_id"]) == {c.case_id for c in s.flow_record.measured()}
    assert prof["depth"].between(0, 1).all() and np.isfinite(prof["v_mean"]).any()
    fields = s.fields
    assert set(fields["case_id"]) == set(s.field_images) == set(s.cases["case_id"])
    assert fields["solid_fraction"].between(0, 1).all() and fields["speed"].max() > 0
    assert (fields["frames"] > 0).all()
    assert '{"control": "cohesionless"}' in set(s.field_null_check["control"])
    assert "CG1 vs CG1" in set(s.field_null_check["comparison"])
    with pytest.raises(LigwfError, match="case_id = 'cg9' has no fields"):
        s.plot_field("cg9")


@pytest.mark.engine
@pytest.mark.mpi
def test_plots_draw_into_the_given_axes_and_return_it(reported):
    from matplotlib.figure import Figure

    s = ligwf.open_study(reported)
    axes = Figure().subplots(1, 5)
    assert s.plot_pareto(axes[0]) is axes[0]
    compared = s.conditions[(s.conditions["cg"] != 1) & s.conditions["angle_error"].notna()]
    assert len(axes[0].containers) == len(compared) > 0        # one error bar per CG-n row
    assert s.plot_pareto(axes[1], metric="profile_error") is axes[1]
    assert s.plot_gsd(axes[2]) is axes[2]
    assert len(axes[2].lines) >= s.gsd["condition"].nunique()
    assert s.plot_profiles(axes[3]) is axes[3]
    assert len(axes[3].lines) >= len(s.profiles["case_id"].unique())
    assert s.plot_kinetics(axes[4], quantity="granules") is axes[4]
    assert len(axes[4].lines) == s.kinetics_summary["condition"].nunique()
    with pytest.raises(LigwfError, match=r"metric = 'nonsense' is not an error .*angle_error"):
        s.plot_pareto(metric="nonsense")
    with pytest.raises(LigwfError, match="quantity = 'd51' is not one of"):
        s.plot_kinetics(quantity="d51")


@pytest.mark.engine
@pytest.mark.mpi
def test_a_plot_without_axes_makes_its_own_pyplot_figure(reported):
    import matplotlib.pyplot as plt

    before = set(plt.get_fignums())
    ax = ligwf.open_study(reported).plot_run_cost()
    assert ax.figure.number in set(plt.get_fignums()) - before and ax.patches
    plt.close(ax.figure)


# ---------------------------------------------------------------- missing outputs
def test_a_rendered_study_names_the_command_for_every_table(rendered):
    s = ligwf.open_study(rendered)
    assert not any(s.available().values())
    for spec in TABLES:
        with pytest.raises(MissingOutput) as err:
            s.table(spec.attribute)
        text = str(err.value)
        assert "\n" not in text and f"`{spec.command} {rendered}`" in text, text
        assert spec.file in text
    for attribute, command in (("summary", "ligwf report"), ("verdict_result", "ligwf report"),
                               ("flow_record", "ligwf analyse"), ("fields", "ligwf analyse"),
                               ("profiles", "ligwf analyse")):
        with pytest.raises(MissingOutput, match=command):
            getattr(s, attribute)
    assert s.paraview == {} and s.figures == {}
    with pytest.raises(LigwfError, match="run `ligwf analyse` first") as err:
        s.check()
    assert "\n" not in str(err.value)


@pytest.mark.engine
@pytest.mark.mpi
def test_check_refuses_a_report_older_than_its_analysis(reported, tmp_path):
    study = tmp_path / "copy"
    shutil.copytree(reported, study)
    record = study / layout.ANALYSIS_DIR / layout.ANALYSIS_RECORD
    report = study / layout.REPORT_DIR / layout.CONDITIONS_REPORT
    os.utime(report, (record.stat().st_mtime - 10,) * 2)
    with pytest.raises(MissingOutput, match="older than the analysis.*run `ligwf report"):
        ligwf.open_study(study).check()


def test_granule_tables_of_a_study_without_granule_data_say_why(rendered, tmp_path):
    study = tmp_path / "dry"
    subprocess.run(["cp", "-r", str(rendered), str(study)], check=True)
    (study / layout.ANALYSIS_DIR).mkdir()
    (study / layout.ANALYSIS_DIR / layout.ANALYSIS_RECORD).write_text(json.dumps(
        {"granules_absent": [{"case_id": "cg1-none-r0", "reason": "dry scene (liquid.model: "
                              "none)"}]}))
    s = ligwf.open_study(study)
    with pytest.raises(MissingOutput, match=r"no gsd table: no granule data by design \(dry"):
        s.gsd
    with pytest.raises(MissingOutput, match="ligwf analyse"):   # not a granule table
        s.flow


def test_a_truncated_table_is_one_line(rendered, tmp_path):
    study = tmp_path / "broken"
    subprocess.run(["cp", "-r", str(rendered), str(study)], check=True)
    (study / layout.ANALYSIS_DIR).mkdir()
    (study / layout.ANALYSIS_DIR / layout.GRANULES_TABLE).write_bytes(b"PAR1\0\0")
    with pytest.raises(MissingOutput) as err:
        ligwf.open_study(study).granules
    assert "unreadable" in str(err.value) and "\n" not in str(err.value)


def test_open_study_refuses_what_is_no_study(tmp_path, rendered):
    with pytest.raises(ConfigError, match="not a ligwf study folder"):
        ligwf.open_study(tmp_path)
    with pytest.raises(ConfigError, match="a case folder, not a study"):
        ligwf.open_study(rendered / "cg1-none-r0")
    with pytest.raises(LigwfError, match="no table 'gsds'"):
        ligwf.open_study(rendered).table("gsds")


# ---------------------------------------------------------------- flow fields
def synthetic_fields(n: int = 8) -> CaseFields:
    """A case whose material fills the lower half (v < 0) of the grid: solid fraction
    0.4, velocity (0.1, 0) m/s, no fluctuation; two identical frames."""
    grid = FieldGrid(origin=-0.01, spacing=0.02 / (n - 1), nodes=n, width=0.002,
                     length=0.01, axis="y")
    sums = np.zeros((2, 5, n, n))
    lower = grid.coordinates() < 0                    # rows: v (the arrays are (v, u))
    sums[:, 0, lower, :] = 0.4
    sums[:, 1, lower, :] = 0.4 * 0.1
    return CaseFields("cg1-none-r0", 1.0, "none", 0, "{}", grid, np.array([10, 20]), sums)


def test_fields_table_puts_each_node_at_its_u_and_v():
    table = fields_table({"cg1-none-r0": synthetic_fields()})
    assert len(table) == 64 and set(table["frames"]) == {2}
    below, above = table[table["v"] < 0], table[table["v"] > 0]
    assert np.allclose(below["solid_fraction"], 0.4) and np.allclose(above["solid_fraction"], 0)
    assert np.allclose(below["velocity_u"], 0.1) and above["velocity_u"].isna().all()
    assert np.allclose(below["temperature"], 0) and table["case_id"].dtype == "string"


def test_plot_field_draws_the_report_map_and_refuses_an_unknown_field():
    from matplotlib.figure import Figure

    ax = Figure().subplots()
    assert plot_field(ax, synthetic_fields(), "speed") is ax
    assert ax.collections and "speed" in ax.get_title()
    with pytest.raises(LigwfError, match="quantity = 'phi' is not one of solid_fraction"):
        plot_field(None, synthetic_fields(), "phi")


# ---------------------------------------------------------------- typing rules
def test_typed_gives_text_flags_and_numbers(tmp_path):
    raw = pd.DataFrame({"case_id": ["a", "b"], "reason": [np.nan, np.nan],
                        "largest_percolates": [True, np.nan], "x": ["1.5", "2"],
                        "angle_error_vs_floor": [np.nan, "within"], "n": [1, 2]},
                       ).astype({"largest_percolates": object, "x": object})
    t = typed(raw)
    assert t.dtypes.to_dict() == {"case_id": "string", "reason": "string",
                                  "largest_percolates": "boolean", "x": "float64",
                                  "angle_error_vs_floor": "string", "n": "int64"}
    path = tmp_path / "t.csv"
    raw.to_csv(path, index=False)
    assert read_table(path).dtypes.to_dict() == t.dtypes.to_dict()
    path.write_text("")
    assert read_table(path).empty


# ---------------------------------------------------------------- public names
def test_every_public_name_imports_and_import_ligwf_loads_no_stage():
    code = ("import sys, ligwf\n"
            "assert 'ligwf.api' not in sys.modules and 'pandas' not in sys.modules\n"
            "from ligwf import *\n"
            "assert all(n in globals() for n in ligwf.__all__), ligwf.__all__\n"
            "assert set(ligwf.__all__) <= set(dir(ligwf))\n"
            "from ligwf import open_study, StudyResults\n"
            "import ligwf.api\n"
            "assert open_study is ligwf.api.open_study and 'pandas' in sys.modules\n")
    proc = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True)
    assert proc.returncode == 0, proc.stderr
    with pytest.raises(AttributeError, match="no attribute 'nonsense'"):
        ligwf.nonsense    # noqa: B018
    assert (ROOT / "ligwf" / "py.typed").is_file()


def test_every_table_layout_names_is_an_api_table():
    """A new table in ligwf.study.layout (a .csv / .parquet name) must reach the API: a
    TableSpec and its property (the notebook test then reads it too)."""
    names = {getattr(layout, n) for n in dir(layout) if n.isupper()
             and isinstance(getattr(layout, n), str)
             and getattr(layout, n).endswith((".csv", ".parquet"))}
    names.discard(layout.THERMO_FILE)      # a case's engine log table, not a study output
    names.discard(layout.CALIBRATION_TABLE)    # ligwf calibrate's own folder, not a study's
    assert names == {t.file for t in TABLES}
    for spec in TABLES:
        assert isinstance(getattr(ligwf.StudyResults, spec.attribute), property), spec


def test_the_api_names_no_file_itself():
    """Output names belong to ligwf.study.layout: the API asks it for every one (string
    constants other than docstrings hold no file name)."""
    for path in sorted((ROOT / "ligwf" / "api").glob("*.py")):
        assert not file_names_in(path), path


def file_names_in(path) -> list[str]:
    """String constants of a module, docstrings left out, that look like a file name."""
    tree = ast.parse(path.read_text())
    docs = {id(n.body[0].value) for n in ast.walk(tree)
            if isinstance(n, (ast.Module, ast.ClassDef, ast.FunctionDef)) and n.body
            and isinstance(n.body[0], ast.Expr) and isinstance(n.body[0].value, ast.Constant)}
    names = re.compile(r"\w\.(csv|parquet|json|png|html|md|pvd|vtu|npz|vti|vtr)\b")
    return [n.value for n in ast.walk(tree) if isinstance(n, ast.Constant) and id(n) not in docs
            and isinstance(n.value, str) and names.search(n.value)]


def test_the_file_name_check_sees_a_literal_and_skips_docstrings(tmp_path):
    fake = tmp_path / "fake.py"
    fake.write_text('"""Reads gsd.csv."""\nNAME = "gsd.csv"\n\n\ndef f():\n    """From x.json."""\n')
    assert file_names_in(fake) == ["gsd.csv"]
