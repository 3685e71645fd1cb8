"""A restart the runner cannot use is said, not skipped silently (issue 32, item 4)."""

from __future__ import annotations

import struct

from helpers import ROOT
from ligwf.cli.main import main
from ligwf.cli.run import unreadable_restarts
from ligwf.study.manifest import Manifest
from ligwf.study.study import Study

TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"


def restart_header(step: int) -> bytes:
    """The header of a LIGGGHTS 3.8.0 restart file (ligwf.engine.liggghts.restart_step)."""
    version = b"LIGGGHTS-PUBLIC 3.8.0"
    return (struct.pack("<ii", 0, len(version)) + version
            + b"".join(struct.pack("<ii", k, 4) for k in (1, 2, 3))
            + struct.pack("<ii", 4, 2) + b"si" + struct.pack("<iq", 5, step) + bytes(64))


def test_a_truncated_restart_is_named_with_what_the_case_does_instead(tmp_path):
    out = tmp_path / "study"
    assert main(["render", str(TINY), "--out", str(out), "--set", "sweep.rules=[bond]"]) == 0
    case = Study.open(out).cases[0]
    case.write_manifest(Manifest(case_id=case.case_id, index=case.index,
                                 scene_hash=case.scene_hash, ligwf_version="",
                                 liggghts_version="", status="killed", steps_done=3000,
                                 total_steps=case.scaled.total_steps))
    (case.path / "restart").mkdir(exist_ok=True)
    (case.path / "restart" / "restart_a.liggghts").write_bytes(b"")
    (case.path / "restart" / "restart_b.liggghts").write_bytes(restart_header(3000)[:12])
    (line,) = unreadable_restarts(Study.open(out).cases, False)
    assert line.startswith(f"{case.case_id}: restart file(s) restart/restart_a.liggghts, "
                           "restart/restart_b.liggghts unreadable")
    assert line.endswith("runs from step 0")
    (case.path / "restart" / "restart_b.liggghts").write_bytes(restart_header(3000))
    (case.path / "restart" / "restart_a.liggghts").unlink()
    assert unreadable_restarts(Study.open(out).cases, False) == []
