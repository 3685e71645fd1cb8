"""Restart identity sidecars, zombie processes and engine error hints (no engine run: the
restart files are written with the header layout of LIGGGHTS 3.8.0, which
``ligwf.engine.liggghts.restart_step`` reads; the engine tests in test_faults.py use real
ones)."""

from __future__ import annotations

import os
import struct
import time

from ligwf.engine.health import HealthIssue, error_hint, verdict
from ligwf.engine.liggghts import restart_step
from ligwf.engine.restart_id import CaseIdentity, sidecar, stamp, why_not_own
from ligwf.study.manifest import FAILED, Manifest, pid_alive, runner_alive
from ligwf.study.processes import start_time

MINE = CaseIdentity("cg3-weber-r0", "a" * 64, 0, (10007, 10009))
OTHER_REPLICA = CaseIdentity("cg3-weber-r1", "a" * 64, 1, (20011, 20021))


def restart_file(path, step: int, body: bytes = b"x" * 4000) -> None:
    version = b"Version LIGGGHTS-PUBLIC 3.8.0"
    head = struct.pack("<ii", 0, len(version)) + version
    for flag in (1, 2, 3):
        head += struct.pack("<ii", flag, 4)
    head += struct.pack("<ii", 4, 2) + b"si" + struct.pack("<iq", 5, step)
    path.write_bytes(head + body)


def test_a_stamped_restart_is_its_case_own_and_nothing_else_is(tmp_path):
    f = tmp_path / "restart_forced_liggghts_1200.data"
    restart_file(f, 1200)
    assert restart_step(f) == 1200
    assert why_not_own(f, MINE, None).startswith("no identity record")
    assert stamp(tmp_path, MINE, 2, time.time() - 5) == [f.name]
    assert stamp(tmp_path, MINE, 2, time.time() - 5) == []      # already describes it
    assert why_not_own(f, MINE, 1200) is None
    assert "another case" in why_not_own(f, OTHER_REPLICA, None)
    assert "past the case's recorded progress" in why_not_own(f, MINE, 1199)
    # a copy of the other replica's restart with its own record is the other's
    g = tmp_path / "other" / "restart_forced_liggghts_1500.data"
    g.parent.mkdir()
    restart_file(g, 1500, b"y" * 4000)
    stamp(g.parent, OTHER_REPLICA, 1, time.time() - 5)
    dropped = tmp_path / g.name
    dropped.write_bytes(g.read_bytes())
    sidecar(dropped).write_bytes(sidecar(g).read_bytes())
    assert "another case" in why_not_own(dropped, MINE, None)


def test_truncated_garbled_or_replaced_restarts_are_refused(tmp_path):
    f = tmp_path / "restart_forced_liggghts_800.data"
    restart_file(f, 800)
    stamp(tmp_path, MINE, 1, time.time() - 5)
    data = f.read_bytes()
    f.write_bytes(data[: len(data) // 2])
    assert "truncated" in why_not_own(f, MINE, None)
    garbled = bytearray(data)
    garbled[-100:-50] = bytes(50)
    f.write_bytes(bytes(garbled))
    assert "SHA-256" in why_not_own(f, MINE, None)


def test_files_older_than_the_attempt_or_still_being_written_are_not_stamped(tmp_path):
    f = tmp_path / "restart_forced_liggghts_400.data"
    restart_file(f, 400)
    assert stamp(tmp_path, MINE, 1, time.time() + 10) == []      # dropped in before it
    assert stamp(tmp_path, MINE, 1, 0.0, settle=30.0) == []       # changed just now
    (tmp_path / "restart_forced_liggghts_500.data").write_bytes(b"not a restart")
    assert stamp(tmp_path, MINE, 1, 0.0) == [f.name]              # unreadable header: no


def test_a_zombie_is_neither_a_live_process_nor_a_live_runner():
    pid = os.fork()
    if pid == 0:
        os._exit(0)
    try:
        deadline = time.monotonic() + 10
        while start_time(pid) is not None and time.monotonic() < deadline:
            time.sleep(0.01)
        with open(f"/proc/{pid}/stat") as fh:            # not reaped yet: a zombie
            assert fh.read().rsplit(")", 1)[1].split()[0] == "Z"
        assert start_time(pid) is None and not pid_alive(pid)
        m = Manifest(case_id="c", index=0, scene_hash="h", ligwf_version="",
                     liggghts_version="", pid=pid, pid_start=None)
        assert not runner_alive(m)
    finally:
        os.waitpid(pid, 0)


def test_the_mesh_internal_error_is_classified_with_a_hint():
    line = "ERROR on proc 0: Internal error (./src/tri_mesh_I.h:109)"
    assert "barycentric" in error_hint(line)
    status, reason = verdict([HealthIssue("error", 272000, line)], 1, 272000, 900000)
    assert status == FAILED and reason.startswith(line)
    assert "dt_rayleigh_fraction" in reason
    assert error_hint("ERROR: Unknown command: bogus") is None


def test_a_hole_in_the_record_is_found_and_bounds_the_resume(tmp_path):
    """record_hole on a rendered case with synthetic rows and dump files (what a full disk
    leaves: a thermo gap, an empty or cut frame, a missing one)."""
    import subprocess
    import sys

    from ligwf.engine.attempt import record_hole
    from ligwf.study.thermo_table import ThermoRow
    from ligwf.study.case import CaseFolder

    from helpers import ROOT

    out = tmp_path / "study"
    r = subprocess.run([sys.executable, "-m", "ligwf.cli.main", "render",
                        str(ROOT / "tests" / "workflows" / "runner_tiny.yaml"), "--out", str(out),
                        "--set", "sweep.rules=[weber]"], capture_output=True, text=True)
    assert r.returncode == 0, r.stderr
    case = CaseFolder.open(out / "cg3-weber-r0")
    s = case.scaled
    rows = [ThermoRow(step, {"step": float(step)}, "production") for step in
            list(range(0, s.total_steps, s.numerics.thermo_every)) + [s.total_steps]]
    steps = case.expected_dump_steps(s.total_steps)
    for step in steps:
        for kind in ("particles", "contacts"):
            (case.path / "post" / f"{kind}_{step}.vtu").write_text(
                '<VTKFile type="UnstructuredGrid">\n</VTKFile>\n')
    assert record_hole(case, rows) is None
    gap = rows[:10] + rows[12:]
    assert record_hole(case, gap) == (rows[9].step, record_hole(case, gap)[1])
    assert "thermo rows missing" in record_hole(case, gap)[1]
    frame = case.path / "post" / f"contacts_{steps[1]}.vtu"
    frame.write_text('<VTKFile type="UnstructuredGrid">\n<Piece')
    assert record_hole(case, rows) == (steps[1] - 1, f"truncated dump {frame.name}")
    frame.write_bytes(b"")
    assert record_hole(case, rows) == (steps[1] - 1, f"empty dump {frame.name}")
    (case.path / "post" / f"particles_{steps[0]}.vtu").unlink()
    assert record_hole(case, rows)[0] == steps[0] - 1
    # a frame past the step the run reached is not judged (it is written again)
    assert record_hole(case, [r for r in rows if r.step < steps[0]]) is None
