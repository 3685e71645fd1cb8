"""Corrupt-output corpus: every kind of damage to a finished study is either FLAGGED in the
report (summary.md lists it with a reason) or REFUSED with one line and exit code 2;
never silently analysed. Plus the re-run scenario: results are replaced as one set or
not at all.

The study is real: the tiny wet drum (tests/workflows/runner_tiny.yaml, 84 particles,
two replicas, four frames each) rendered and run once per module by ``ligwf run`` with
the real engine (so manifests, thermo tables and dump records are the runner's own);
each corruption works on a copy.
"""

from __future__ import annotations

import base64
import json
import re
import shutil
from pathlib import Path
from typing import Callable

import numpy as np
import pytest

from helpers import ROOT
from ligwf.cli.main import main

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"
R0, R1 = "cg3-weber-r0", "cg3-weber-r1"


@pytest.fixture(scope="module")
def study(engine, tmp_path_factory) -> Path:
    out = tmp_path_factory.mktemp("corrupt") / "study"
    assert main(["run", str(TINY), "--out", str(out), "--set", "sweep.rules=[weber]",
                 "--set", "sweep.replicas=2", "--set", "scene.process.run_time=0.2"]) == 0
    rec = json.loads((out / "study.json").read_text())
    rec["analysis"] = {"granules": "communities", "bootstrap": 20}
    (out / "study.json").write_text(json.dumps(rec))
    assert (out / R0 / "dumps.json").is_file(), "a done manifest comes with its dump record"
    return out


@pytest.fixture(scope="module")
def analysed(study, tmp_path_factory) -> Path:
    """The study analysed once by ``ligwf analyse``, for the tests that damage or check its
    analysis outputs (each works on a copy; one analysis instead of one per test)."""
    out = tmp_path_factory.mktemp("analysed") / "study"
    shutil.copytree(study, out)
    assert main(["analyse", str(out)]) == 0
    return out


def post(study: Path, case: str = R0) -> Path:
    return study / case / "post"


def steps(study: Path, case: str = R0) -> list[int]:
    return sorted(int(m.group(1)) for p in post(study, case).iterdir()
                  if (m := re.match(r"particles_(\d+)\.vtu$", p.name)))


def edit_array(path: Path, name: str, fn: Callable[[np.ndarray], np.ndarray]) -> None:
    """Decode one binary DataArray, change its values, re-encode it as valid base64 (the
    header's RangeMin/RangeMax stay as LIGGGHTS wrote them)."""
    text = path.read_text()
    m = re.search(r'(<DataArray type="(\w+)" Name="' + name + r'"[^>]*>\s*)([A-Za-z0-9+/=]+)', text)
    dtype = {"Int32": "<i4", "Float64": "<f8", "Float32": "<f4"}[m.group(2)]
    raw = base64.b64decode(m.group(3))
    arr = fn(np.frombuffer(raw[4:], dtype).copy()).astype(dtype)
    blob = base64.b64encode(np.uint32(arr.nbytes).tobytes() + arr.tobytes()).decode()
    path.write_text(text[:m.start(3)] + blob + text[m.end(3):])


def flip_bit(a: np.ndarray) -> np.ndarray:
    bits = a.view(np.uint32) if a.dtype.itemsize == 4 else a.view(np.uint64)
    bits[len(bits) // 2] ^= type(bits[0])(1 << (30 if a.dtype.itemsize == 4 else 62))
    return a


def permute(a: np.ndarray) -> np.ndarray:
    return np.random.default_rng(1).permutation(a)


def with_nan(a: np.ndarray) -> np.ndarray:
    a[5] = np.nan
    return a


def duplicate_id(a: np.ndarray) -> np.ndarray:
    a[1] = a[0]
    return a


def frame(study: Path, k: int, kind: str = "particles", case: str = R0) -> Path:
    return post(study, case) / f"{kind}_{steps(study, case)[k]}.vtu"


def truncate(path: Path, keep: float = 0.5) -> None:
    path.write_bytes(path.read_bytes()[: int(path.stat().st_size * keep)])


def drop_array(path: Path, name: str) -> None:
    text = path.read_text()
    path.write_text(re.sub(r'<DataArray[^>]*Name="' + name + r'".*?</DataArray>', "", text,
                           count=1, flags=re.S))


def beyond_run(study: Path) -> None:
    s = steps(study)
    last = {kind: frame(study, -1, kind) for kind in ("particles", "contacts")}
    for kind, src in last.items():
        shutil.copy(src, post(study) / f"{kind}_{s[-1] + 10 * (s[1] - s[0])}.vtu")


def off_interval(study: Path) -> None:
    shutil.copy(frame(study, 1), post(study) / f"particles_{steps(study)[1] + 1}.vtu")


def other_replica(study: Path) -> None:
    for kind in ("particles", "contacts"):
        shutil.copy(frame(study, 2, kind, R1), frame(study, 2, kind, R0))


def delete_all_dumps(study: Path) -> None:
    for p in post(study).glob("*.vtu"):
        p.unlink()


def no_record(edit):
    """The same damage to a case run by hand-like means: no dump record to compare with."""
    def apply(study: Path) -> None:
        (study / R0 / "dumps.json").unlink()
        edit(study)
    return apply


# name -> (damage, words one of which summary.md must show for it)
FLAGGED: dict[str, tuple[Callable[[Path], None], tuple[str, ...]]] = {
    "deleted frame": (lambda s: [frame(s, 1, k).unlink() for k in ("particles", "contacts")],
                      ("missing frame: no particle dump",)),
    "particle dump deleted, contact left": (lambda s: frame(s, 1).unlink(),
                                            ("its contact dump",)),
    "contact dump deleted": (lambda s: frame(s, 1, "contacts").unlink(), ("no contact dump",)),
    "permuted ids": (lambda s: edit_array(frame(s, 1), "id", permute), ("SHA-256",)),
    "permuted ids, no record": (no_record(lambda s: edit_array(frame(s, 1), "id", permute)),
                                ("does not match the particle dump",)),
    "flipped bits in valid base64": (lambda s: edit_array(frame(s, 1), "v", flip_bit),
                                     ("SHA-256",)),
    "flipped bits, no record": (no_record(lambda s: edit_array(frame(s, 1), "Points", flip_bit)),
                                ("header says", "outside the drum")),
    # same particle count: equal size (caught by the hash) or a byte apart (by the size)
    "frame of another replica": (other_replica, ("SHA-256", "truncated or replaced")),
    "step beyond the run": (beyond_run, ("not a dump step",)),
    "step off the dump interval": (off_interval, ("not a dump step",)),
    "all dumps of a case deleted": (delete_all_dumps, ("no analysable frame",)),
    "thermo.csv truncated": (lambda s: truncate(s / R0 / "thermo.csv", 0.7), ("thermo.csv",)),
    "thermo.csv deleted": (lambda s: (s / R0 / "thermo.csv").unlink(), ("thermo.csv is missing",)),
    "truncated dump": (lambda s: truncate(frame(s, 1)), ("bytes, the run left",)),
    "truncated dump, no record": (no_record(lambda s: truncate(frame(s, 1))),
                                  ("truncated or corrupt",)),
    "empty dump": (lambda s: frame(s, 1).write_bytes(b""), ("bytes, the run left",)),
    "empty dump, no record": (no_record(lambda s: frame(s, 1).write_bytes(b"")), ("empty",)),
    "garbage dump, no record": (no_record(lambda s: frame(s, 1).write_bytes(
        np.random.default_rng(2).bytes(5000))), ("not a readable VTU",)),
    "garbage contact dump, no record": (no_record(lambda s: frame(s, 2, "contacts").write_text(
        "<VTKFile>garbage")), ("not a readable VTU",)),
    "missing array": (lambda s: drop_array(frame(s, 1), "radius"), ("bytes, the run left",)),
    "missing array, no record": (no_record(lambda s: drop_array(frame(s, 1), "radius")),
                                 ("lacks the array",)),
    "nan values, no record": (no_record(lambda s: edit_array(frame(s, 1), "v", with_nan)),
                              ("nan or inf",)),
    "duplicate ids, no record": (no_record(lambda s: edit_array(frame(s, 1), "id", duplicate_id)),
                                 ("duplicate particle ids", "header says")),
    "contact dump of another frame, no record": (no_record(lambda s: shutil.copy(
        frame(s, 0, "contacts"), frame(s, 1, "contacts"))), ("does not match the particle dump",)),
    "id out of range, no record": (no_record(lambda s: edit_array(
        frame(s, 1), "id", lambda a: np.where(a == a.max(), 999, a))), ("header says", "ids")),
    "dump record truncated": (lambda s: truncate(s / R0 / "dumps.json"), ("unreadable dump record",)),
    "scene record truncated": (lambda s: truncate(s / R0 / "scene.json"),
                               ("not a readable case folder",)),
    "scene record garbage": (lambda s: (s / R0 / "scene.json").write_text("[1, 2"),
                             ("not a readable case folder",)),
    "manifest truncated": (lambda s: truncate(s / R0 / "manifest.json"), ("unreadable manifest",)),
    "manifest garbage": (lambda s: (s / R0 / "manifest.json").write_text('"done"'),
                         ("unreadable manifest",)),
    "case folder deleted": (lambda s: shutil.rmtree(s / R0), ("not a readable case folder",)),
}


def run(capsys, *argv: str) -> tuple[int, str]:
    code = main(list(argv))
    err = capsys.readouterr().err
    assert "Traceback" not in err
    return code, err


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("name", list(FLAGGED))
def test_corruption_is_flagged_in_the_report(study, tmp_path, capsys, name):
    damage, words = FLAGGED[name]
    copy = tmp_path / "study"
    shutil.copytree(study, copy)
    damage(copy)
    code, _ = run(capsys, "analyse", str(copy))
    assert code == 0, "the other replica is still analysable"
    code, err = run(capsys, "report", str(copy), "--no-snapshots")
    assert code == 0 and "the report lists" in err
    summary = (copy / "report" / "summary.md").read_text()
    problems = summary[summary.index("## Skipped cases"):summary.index("## Figures")]
    assert any(w in problems for w in words), problems
    assert R0 in problems
    assert any(w in (copy / "report" / "index.html").read_text() for w in words)


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("target,content", [("study.json", None), ("study.json", "{]"),
                                            ("study.json", "[]")])
def test_broken_study_record_is_refused(study, tmp_path, capsys, target, content):
    copy = tmp_path / "study"
    shutil.copytree(study, copy)
    if content is None:
        truncate(copy / target)
    else:
        (copy / target).write_text(content)
    for cmd in (["analyse", str(copy)], ["report", str(copy), "--no-snapshots"]):
        code, err = run(capsys, *cmd)
        assert code == 2 and len(err.strip().splitlines()) == 1, err


@pytest.mark.engine
@pytest.mark.mpi
def test_nothing_analysable_is_refused_and_keeps_results(analysed, tmp_path, capsys):
    copy = tmp_path / "study"
    shutil.copytree(analysed, copy)
    before = {p.name: p.read_bytes() for p in (copy / "analysis").iterdir() if p.is_file()}
    for case in (R0, R1):
        for p in post(copy, case).glob("*.vtu"):
            p.unlink()
    code, err = run(capsys, "analyse", str(copy))
    assert code == 2 and "nothing analysed" in err and len(err.strip().splitlines()) == 1
    assert {p.name: p.read_bytes() for p in (copy / "analysis").iterdir() if p.is_file()} == before


@pytest.mark.engine
@pytest.mark.mpi
@pytest.mark.parametrize("output", ["gsd.csv", "frames.csv", "analysis.json", "analysis",
                                    "flow_profiles.json"])
def test_deleted_analysis_output_is_flagged(analysed, tmp_path, capsys, output):
    """A deleted granule table is listed in the report; without the analysis record or the
    flow record (the report reads its flow metrics from the analysis) the report refuses in
    one line and says to run ``ligwf analyse``."""
    copy = tmp_path / "study"
    shutil.copytree(analysed, copy)
    target = copy / "analysis" / output if output != "analysis" else copy / "analysis"
    shutil.rmtree(target) if target.is_dir() else target.unlink()
    code, err = run(capsys, "report", str(copy), "--no-snapshots")
    if output in ("gsd.csv", "frames.csv"):
        assert code == 0 and "analysis output problem" in err
        assert f"{output} missing" in (copy / "report" / "summary.md").read_text()
    else:
        lines = err.strip().splitlines()
        assert code == 2 and len(lines) == 1 and "ligwf analyse" in lines[0], err


@pytest.mark.engine
@pytest.mark.mpi
def test_rerun_replaces_results_as_a_set(study, tmp_path, capsys):
    """analyse --no-manifest-check, then analyse with the check on cases run by hand:
    the second is refused (exit 2, one line) and the first's outputs stay whole; a run
    with --no-vtu leaves no stale series; no staging folder is left behind."""
    copy = tmp_path / "study"
    shutil.copytree(study, copy)
    for case in (R0, R1):
        (copy / case / "manifest.json").unlink()
    out = copy / "analysis"
    assert run(capsys, "analyse", str(copy), "--no-manifest-check")[0] == 0
    first = {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()}
    assert any(p.suffix == ".vtu" for p in first)
    code, err = run(capsys, "analyse", str(copy))
    assert code == 2 and len(err.strip().splitlines()) == 1
    assert {p.relative_to(out): p.read_bytes() for p in out.rglob("*") if p.is_file()} == first
    for name in ("frames.csv", "gsd.csv", "gsd_summary.csv"):
        assert (out / name).stat().st_size > 100
    assert run(capsys, "analyse", str(copy), "--no-manifest-check", "--no-vtu")[0] == 0
    assert not list(out.rglob("*.vtu")) and not list(out.rglob("*.pvd"))
    assert not [p for p in out.iterdir() if p.name.startswith(".")]
