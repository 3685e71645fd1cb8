"""Studies that must finish, and results that must not be silently wrong (issue 21).

Real runs only: a tiny Bond-scaled CG3 study (tests/workflows/runner_tiny.yaml on a 12 mm
slice, 56 particles, two replicas, 0.3 s of production with a frame every 0.02 s; ~4 s a
case on one core) run once per module with ``ligwf run`` and analysed with ``ligwf
analyse``; every damage works on a copy. The dry and ``contact_dumps: false`` studies are the
same drum run through ``ligwf study``.
"""

from __future__ import annotations

import csv
import io
import json
import shutil
from pathlib import Path

import numpy as np
import pytest

import ligwf
from helpers import ROOT
from ligwf.analysis.frames.dumps import read_particles
from ligwf.analysis.flow.frame import DrumGeometry, cross_section, rising_side
from ligwf.analysis.flow.surface import SurfaceFit, fit_surface
from ligwf.analysis.records.provenance import StaleAnalysis
from ligwf.cli.main import main
from ligwf.study.case import CaseFolder

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"
BOND = ["--set", "sweep.rules=[bond]", "--set", "sweep.replicas=2",
        "--set", "scene.drum.length=0.012", "--set", "scene.process.run_time=0.3",
        "--set", "scene.numerics.dump_interval=0.02"]
R0, R1 = "cg3-bond-r0", "cg3-bond-r1"
DRY = ["--set", "scene.liquid={model: none}", "--set", "sweep.rules=[none]",
       "--set", "scene.analysis.contact_dumps=false"]


def run(capsys, *argv: str) -> tuple[int, str, str]:
    code = main(list(argv))
    cap = capsys.readouterr()
    assert "Traceback" not in cap.err
    return code, cap.out, cap.err


def one_line(err: str) -> str:
    lines = err.strip().splitlines()
    assert len(lines) == 1, err
    return lines[0]


@pytest.fixture(scope="module")
def study(engine, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("integrity") / "study"
    assert main(["run", str(TINY), "--out", str(out), "--np", "1", *BOND]) == 0
    rec = json.loads((out / "study.json").read_text())
    rec["analysis"] = {"granules": "communities", "bootstrap": 20, "sensitivity_frames": 0}
    (out / "study.json").write_text(json.dumps(rec))
    assert main(["analyse", str(out), "--no-vtu"]) == 0
    return out


@pytest.fixture
def copy(study, tmp_path) -> Path:
    dst = tmp_path / "study"
    shutil.copytree(study, dst)
    return dst


# ---------------------------------------------------------------- studies that must finish
@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("kind,args,words", [
    ("dry", DRY, "dry scene (liquid.model: none)"),
    ("granules off", ["--set", "sweep.rules=[weber]", "--set", "scene.analysis.contact_dumps=false"],
     "scene.analysis.contact_dumps: false"),
])
def test_study_without_granule_data_ends_with_a_flow_report(engine, tmp_path, capsys, kind,
                                                            args, words):
    code, out, _ = run(capsys, "check", str(TINY), *args)
    assert code == 0 and "NO granules, GSD or kinetics" in out and words in out
    assert "flow metrics (angle of repose" in out
    study = tmp_path / "study"
    code, out, err = run(capsys, "study", str(TINY), "--out", str(study), "--np", "1",
                         "--no-snapshots", *args)
    assert code == 0, err
    summary = (study / "report" / "summary.md").read_text()
    granules = summary[summary.index("## Granules"):summary.index("## Figures")]
    assert words in granules and "flow metrics are complete" in granules
    cases = list(csv.DictReader(io.StringIO((study / "report" / "cases.csv").read_text())))
    assert cases and all(np.isfinite(float(c["angle_of_repose"])) for c in cases)
    assert all(c["rigid_frame_share"] != "" for c in cases)
    assert "## Analysis outputs\n\ncomplete" in summary
    assert not (study / "analysis" / "gsd.csv").exists()


@pytest.mark.engine
@pytest.mark.mpi
def test_surface_fit_second_pass_too_few_strips_keeps_the_first_line(study):
    """At a span of 0.68 the second pass of these real Bond frames finds 3 strips; the fit
    must still be a SurfaceFit (it was the first pass's raw tuple: flow.py AttributeError)."""
    case = CaseFolder.open(study / R0)
    geo = DrumGeometry.from_scaled(case.scaled)
    fits = []
    for p in sorted((case.path / "post").glob("particles_*.vtu")):
        step = int(p.stem.split("_")[1])
        frame = read_particles(p, step, case.scaled.numerics.dt)
        u, v, _, _ = cross_section(frame, geo)
        fits.append(fit_surface(u, v, frame.radii, geo.radius, geo.d_mean, rising_side(geo),
                                span=0.68))
    assert fits and all(f is None or isinstance(f, SurfaceFit) for f in fits), fits
    assert any(isinstance(f, SurfaceFit) for f in fits)


# ---------------------------------------------------------------- stale or foreign analysis
@pytest.mark.engine
@pytest.mark.mpi
def test_stale_and_foreign_analysis_is_refused(study, copy, tmp_path, capsys):
    assert run(capsys, "report", str(copy), "--no-snapshots")[0] == 0   # fresh: fine
    other = tmp_path / "other"
    shutil.copytree(study, other)
    # re-run with another rpm: cases re-rendered and run again, analysis/ left as it was
    assert main(["run", str(TINY), "--out", str(other), "--np", "1", *BOND,
                 "--set", "scene.process.rotation.rpm=40", "--replace"]) == 0
    capsys.readouterr()
    code, _, err = run(capsys, "report", str(other), "--no-snapshots")
    line = one_line(err)
    assert code == 2 and "stale" in line and "scene changed" in line, line
    # the other study's fresh analysis copied into this one
    assert run(capsys, "analyse", str(other), "--no-vtu")[0] == 0
    shutil.rmtree(copy / "analysis")
    shutil.copytree(other / "analysis", copy / "analysis")
    code, _, err = run(capsys, "report", str(copy), "--no-snapshots")
    assert code == 2 and "scene changed" in one_line(err)
    # settings changed since the analysis
    shutil.rmtree(copy / "analysis")
    shutil.copytree(study / "analysis", copy / "analysis")
    rec = json.loads((copy / "study.json").read_text())
    rec["analysis"]["bootstrap"] = 30
    (copy / "study.json").write_text(json.dumps(rec))
    code, _, err = run(capsys, "report", str(copy), "--no-snapshots")
    assert code == 2 and "settings changed" in one_line(err)


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("table", ["gsd.csv", "granules.parquet", "frames.csv"])
def test_truncated_analysis_table_is_refused(copy, capsys, table):
    path = copy / "analysis" / table
    path.write_bytes(path.read_bytes()[: path.stat().st_size // 2])
    code, _, err = run(capsys, "report", str(copy), "--no-snapshots")
    line = one_line(err)
    assert code == 2 and table in line and "truncated" in line, line


# ---------------------------------------------------------------- edited records
@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("edit,field", [
    (lambda r: r["scaled"].update(contact_angle_deg=40.0), "scaled.contact_angle_deg"),
    (lambda r: r["scaled"].update(dt=r["scaled"]["dt"] * 0.5), "scaled.dt"),
    (lambda r: r.update(cg=2.0), "cg = 2.0"),
    # the original block (not under the content hash) no longer gives the scaled one
    (lambda r: r["scene"]["liquid"].update(surface_tension=0.24),
     "scaled.surface_tension = 0.216 (its scene gives 2.16)"),
])
def test_edited_scene_record_is_refused_naming_the_field(copy, capsys, edit, field):
    path = copy / R0 / "scene.json"
    rec = json.loads(path.read_text())
    edit(rec)
    path.write_text(json.dumps(rec))
    code, _, err = run(capsys, "analyse", str(copy), "--no-vtu")
    assert code == 0 and f"skipped case {R0}" in err and field in err, err
    code, _, err = run(capsys, "report", str(copy), "--no-snapshots")
    assert code == 0 and "the report lists 1 skipped case" in err
    summary = (copy / "report" / "summary.md").read_text()
    assert field in summary[summary.index("## Skipped cases"):summary.index("## Skipped or")]
    assert field in dict(ligwf.open_study(copy).check().cases)[R0]     # the API alike


def _thermo_rows(path: Path) -> list[str]:
    return path.read_text().splitlines(keepends=True)


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("damage,words", [
    (lambda rows: rows[:20] + [rows[20].replace(rows[20].split(",")[3], "nan", 1)] + rows[21:],
     "no finite"),
    (lambda rows: rows[:20] + [rows[20]] + rows[20:], "duplicated or out of order"),
    (lambda rows: rows[:20] + rows[25:], "rows missing between steps"),
    # the atom count falls near the end (56 -> 40): a done run never loses a particle
    (lambda rows: rows[:-3] + [_with_atoms(r, 40) for r in rows[-3:]],
     "the atom count falls from 56 to 40"),
])
def test_damaged_thermo_table_is_a_skipped_case(copy, capsys, damage, words):
    path = copy / R0 / "thermo.csv"
    path.write_text("".join(damage(_thermo_rows(path))))
    code, _, err = run(capsys, "analyse", str(copy), "--no-vtu")
    assert code == 0 and f"skipped case {R0}: thermo.csv" in err and words in err, err
    code, _, err = run(capsys, "report", str(copy), "--no-snapshots")
    assert code == 0
    assert words in (copy / "report" / "summary.md").read_text()
    assert words in dict(ligwf.open_study(copy).check().cases)[R0]     # the API alike


def _with_atoms(row: str, atoms: int) -> str:
    cells = row.split(",")
    cells[2] = f"{atoms}.0"                       # step,time,atoms,...
    return ",".join(cells)


@pytest.mark.engine
@pytest.mark.mpi
def test_a_same_size_edit_of_a_contact_dump_is_refused_by_report_and_check(copy, capsys):
    """Every dump kind the analysis read is hashed again (a contact dump was not)."""
    dump = sorted((copy / R0 / "post").glob("contacts_*.vtu"))[-1]
    data = bytearray(dump.read_bytes())
    i = len(data) // 2
    data[i] = ord("1") if data[i] != ord("1") else ord("2")
    dump.write_bytes(bytes(data))
    code, _, err = run(capsys, "report", str(copy), "--no-snapshots")
    line = one_line(err)
    assert code == 2 and dump.name in line and "content differs" in line, line
    with pytest.raises(StaleAnalysis, match=f"{dump.name}: content differs"):
        ligwf.open_study(copy).check()


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("tail,status,words", [
    (b"", "duplicate", "byte for byte the particle dump of step"),
    (b"\n", "skipped", "every particle position is that of the frame of step"),  # array copy
])
def test_a_frame_copied_over_the_next_is_a_skipped_frame(copy, capsys, tail, status, words):
    """Without a dump record (a case run by hand), a frame that is a copy of the one before
    it (byte for byte, or its arrays in other bytes) is refused by the analysis and listed
    by the report, not used twice."""
    (copy / R0 / "dumps.json").unlink()
    post = copy / R0 / "post"
    steps = sorted(int(p.stem.split("_")[1]) for p in post.glob("particles_*.vtu"))
    a, b = steps[-3], steps[-2]
    for kind in ("particles", "contacts"):
        (post / f"{kind}_{b}.vtu").write_bytes((post / f"{kind}_{a}.vtu").read_bytes() + tail)
    code, _, err = run(capsys, "analyse", str(copy), "--no-vtu")
    assert code == 0 and f"{status} frame {R0} step {b}" in err, err
    frames = list(csv.DictReader(io.StringIO((copy / "analysis" / "frames.csv").read_text())))
    (row,) = [f for f in frames if f["case_id"] == R0 and int(f["step"]) == b]
    assert row["status"] == status and f"{words} {a}" in row["reason"], row
    code, _, err = run(capsys, "report", str(copy), "--no-snapshots")
    assert code == 0, err
    summary = (copy / "report" / "summary.md").read_text()
    frames_section = summary[summary.index("## Skipped or"):summary.index("## Analysis outputs")]
    assert f"| {R0} | {b} | {status} |" in frames_section


# ---------------------------------------------------------------- swapped, listed twice
@pytest.mark.engine
@pytest.mark.mpi
def test_swapped_post_folders_end_in_one_line(copy, capsys):
    (copy / R0 / "post").rename(copy / "tmp-post")
    (copy / R1 / "post").rename(copy / R0 / "post")
    (copy / "tmp-post").rename(copy / R1 / "post")
    code, _, err = run(capsys, "report", str(copy), "--no-snapshots")
    line = one_line(err)
    assert code == 2 and "nothing to report" in line and "the run left" in line, line
    code, _, err = run(capsys, "analyse", str(copy))
    assert code == 2 and "nothing analysed" in one_line(err)


@pytest.mark.engine
@pytest.mark.mpi
def test_case_listed_twice_ends_in_one_line(copy, capsys):
    rec = json.loads((copy / "study.json").read_text())
    rec["cases"].append(dict(rec["cases"][0], index=len(rec["cases"])))
    (copy / "study.json").write_text(json.dumps(rec))
    for cmd in (["report", str(copy), "--no-snapshots"], ["analyse", str(copy)]):
        code, _, err = run(capsys, *cmd)
        line = one_line(err)
        assert code == 2 and f"lists case {R0} more than once" in line, line


# ---------------------------------------------------------------- mesh cache
def test_truncated_mesh_in_the_cache_is_not_copied_into_a_case(tmp_path, capsys):
    cache = tmp_path / "meshes"
    first = tmp_path / "first"
    assert run(capsys, "render", str(TINY), "--out", str(first), "--mesh-cache", str(cache),
               "--set", "sweep.rules=[weber]")[0] == 0
    (stl,) = cache.glob("*.stl")
    good = stl.read_bytes()
    stl.write_bytes(good[: len(good) // 3])
    second = tmp_path / "second"
    assert run(capsys, "render", str(TINY), "--out", str(second), "--mesh-cache", str(cache),
               "--set", "sweep.rules=[weber]")[0] == 0
    assert (second / "cg3-weber-r0" / "drum.stl").read_bytes() == good
    assert stl.read_bytes() == good
    # a truncated mesh inside a rendered case: its scene hash no longer holds
    case = second / "cg3-weber-r0"
    (case / "drum.stl").write_bytes(good[: len(good) // 3])
    why = CaseFolder.open(case).record_problem()
    assert why is not None and "drum.stl" in why
