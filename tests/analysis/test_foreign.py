"""``ligwf analyse-dumps`` and the Python API on dumps ligwf did not write: every fact of the
run is required (clear one-line errors), nothing defaults to step 0 or a box length of 0."""

from __future__ import annotations

import json
import shutil
from pathlib import Path

import pandas as pd
import pytest

from ligwf.analysis.granules.case import RunFacts
from ligwf.analysis.frames.dumps import read_contacts, read_particles
from ligwf.analysis.granules.bridge_law import Liquid
from ligwf.cli.main import main
from ligwf.scene.axis import Axis
from ligwf.errors import ConfigError, DumpReadError
from ligwf.study import layout
from wetdump import wet_study

ARGS = ["--liquid", "washino", "--surface-tension", "0.216", "--contact-angle", "30",
        "--angle-convention", "scene", "--periodic-axis", "y", "--box-length", "0.009",
        "--dt", "2e-5", "--set", "granules=communities"]   # the run is shorter than held's 1 s


@pytest.fixture(scope="module")
def dumps(engine, tmp_path_factory) -> Path:
    """The wet case's dumps alone, as a user would bring them (no scene, no manifest)."""
    out = tmp_path_factory.mktemp("foreign") / "dumps"
    shutil.copytree(wet_study(engine, tmp_path_factory) / "cg3-weber-r0" / "post", out)
    return out


@pytest.mark.engine
@pytest.mark.mpi
def test_analyse_dumps_matches_the_case_analysis(dumps, tmp_path, capsys):
    out = tmp_path / "out"
    assert main(["analyse-dumps", str(dumps), "--out", str(out), "--cg", "3", *ARGS]) == 0
    g = pd.read_parquet(out / "granules.parquet")
    frames = pd.read_csv(out / "frames.csv")
    assert (frames["status"] == "ok").all() and (g.groupby("step")["members"].sum() == 222).all()
    assert g["percolating"].dtype == bool and (out / "dumps" / "granules.pvd").is_file()


@pytest.mark.engine
@pytest.mark.mpi
def test_analyse_dumps_writes_every_output_analyse_does(dumps, engine, tmp_path_factory,
                                                       tmp_path):
    """The same granule stage for both frame sources: analyse-dumps writes every output of
    ``ligwf analyse`` but those a foreign run cannot have (the flow stage's metrics and
    fields: no drum; controls: no twin), which its record names."""
    study = tmp_path / "study"
    shutil.copytree(wet_study(engine, tmp_path_factory), study)
    assert main(["analyse", str(study)]) == 0
    out = tmp_path / "out"
    assert main(["analyse-dumps", str(dumps), "--out", str(out), "--cg", "3", *ARGS]) == 0
    ours = {p.name for p in (study / "analysis").iterdir() if p.is_file()}
    theirs = {p.name for p in out.iterdir() if p.is_file()}
    flow_stage = {layout.FLOW_TABLE, layout.FLOW_PROFILES, layout.FIELDS_DATA,
                  *(layout.field_image(c) for c in ("cg3-weber-r0", "cg3-weber-r1"))}
    assert flow_stage <= ours, ours                     # the flow stage's outputs, fields too
    assert theirs == ours - flow_stage, (ours, theirs)
    assert {layout.KINETICS_TABLE, layout.KINETICS_SUMMARY_TABLE, layout.SENSITIVITY_TABLE,
            layout.GSD_POOLING_TABLE} <= theirs
    assert len(pd.read_csv(out / layout.KINETICS_TABLE)) == len(pd.read_csv(out / "frames.csv"))
    assert len(pd.read_csv(out / layout.SENSITIVITY_TABLE)) >= 1
    record = json.loads((out / layout.ANALYSIS_RECORD).read_text())
    assert "drum" in record["flow"] and "twin" in record["controls"]
    series = {p.name for p in (out / "dumps").iterdir()}
    assert layout.GRANULE_SERIES in series and any(layout.granule_frame_step(n) for n in series)


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("drop,message", [
    ("--box-length", "--box-length"), ("--surface-tension", "--surface-tension"),
    ("--contact-angle", "--contact-angle")])
def test_missing_facts_are_one_line_errors(dumps, tmp_path, capsys, drop, message):
    i = ARGS.index(drop)
    args = ARGS[:i] + ARGS[i + 2:]
    assert main(["analyse-dumps", str(dumps), "--out", str(tmp_path / "o"), *args]) == 2
    err = capsys.readouterr().err
    assert message in err and "Traceback" not in err and len(err.strip().splitlines()) == 1
    assert not (tmp_path / "o").exists()


@pytest.mark.engine
@pytest.mark.mpi
def test_a_run_shorter_than_the_hold_window_is_refused_naming_it(dumps, tmp_path, capsys):
    args = ARGS[:ARGS.index("--set")]                    # granules: held, hold_time 1 s
    assert main(["analyse-dumps", str(dumps), "--out", str(tmp_path / "o"), *args]) == 2
    err = " ".join(capsys.readouterr().err.split())
    assert "analysis.hold_time = 1 s" in err and "hold window" in err and "Traceback" not in err
    assert not (tmp_path / "o").exists()


def test_the_gsd_and_hold_windows_are_checked_against_the_frames(tmp_path):
    from ligwf.analysis.foreign import check_window
    from ligwf.analysis.frames.dumps import FrameFiles
    from ligwf.scene.settings import AnalysisSettings

    frames = [FrameFiles(s, tmp_path / f"particles_{s}.vtu", None) for s in (0, 500, 1000)]
    held = AnalysisSettings(granules="held", hold_time=0.005)
    check_window(frames, 1e-5, held, 1000)                         # 0.01 s >= 0.005 s
    with pytest.raises(ConfigError, match=r"after the last frame \(step 1000\); allowed "
                       r"range \[0, 1000\]"):
        check_window(frames, 1e-5, held, 10**12)
    with pytest.raises(ConfigError, match=r"hold_time = 0.02 s: the dumps span 0.01 s"):
        check_window(frames, 1e-5, AnalysisSettings(granules="held", hold_time=0.02), 0)
    check_window(frames, 1e-5, AnalysisSettings(granules="communities", hold_time=0.02), 0)


def test_required_options_refused_by_the_parser(tmp_path, capsys):
    try:
        code = main(["analyse-dumps", str(tmp_path), "--liquid", "washino"])
    except SystemExit as exc:          # argparse's own exit, or ligwf's usage-error line
        code = exc.code
    assert code == 2 and "--angle-convention" in capsys.readouterr().err


def test_no_silent_defaults_in_the_python_api(tmp_path):
    bad = tmp_path / "frame.vtu"
    bad.write_text("x")
    with pytest.raises(DumpReadError, match="no step in the file name"):
        read_particles(bad)
    with pytest.raises(DumpReadError, match="no step in the file name"):
        read_contacts(bad)
    with pytest.raises(ConfigError, match="box length"):
        RunFacts("foreign", 1.0, Liquid("washino", 0.02, 0.5, 0.02), Axis.Y, 0.0, 1e-5)
    with pytest.raises(ConfigError, match="time step"):
        RunFacts("foreign", 1.0, Liquid("washino", 0.02, 0.5, 0.02), None, 0.0, 0.0)


def test_two_dumps_of_one_step_are_refused_naming_both(tmp_path, capsys):
    """particles_13618.vtu and particles_013618.vtu are one step: which to analyse would be
    a guess (the folder's listing order), so the command names both and stops, nothing
    written. On the committed real CG3 dumps (tests/data/cg3_slice)."""
    from helpers import ROOT

    real = ROOT / "tests" / "data" / "cg3_slice" / "cg3-weber-r0" / "post"
    dumps = tmp_path / "dumps"
    shutil.copytree(real, dumps)
    shutil.copy2(dumps / "particles_13618.vtu", dumps / "particles_013618.vtu")
    out = tmp_path / "out"
    assert main(["analyse-dumps", str(dumps), "--out", str(out), "--cg", "3", *ARGS]) != 0
    err = capsys.readouterr().err.strip().splitlines()
    assert len(err) == 1 and "Traceback" not in err[0], err
    assert "particles_013618.vtu and particles_13618.vtu are both step 13618" in err[0]
    assert not out.exists()
    (dumps / "particles_013618.vtu").unlink()              # one per step: it runs
    assert main(["analyse-dumps", str(dumps), "--out", str(out), "--cg", "3", *ARGS]) == 0
    assert (pd.read_csv(out / "frames.csv")["status"] == "ok").all()
