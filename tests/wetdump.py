"""Real LIGGGHTS dumps for the analysis tests, made once per test session.

A CG3 Weber-scaled slice of workflows/demo.yaml (222 particles, 0.05 s settling, 0.2 s
production, a particle and a contact .vtu every 0.05 s) is rendered and run on 2 ranks
(~8 s). The study folder also gets a replica copy and a failed case, with manifests.
"""

from __future__ import annotations

import dataclasses
import json
import shutil
from pathlib import Path

from helpers import DRUM, run_liggghts
from ligwf.pipeline.prepare import render_workflow, write_study
from ligwf.scene.workflow import load_workflow
from ligwf.study.made_from import sealed
from ligwf.study.study_record import CaseEntry, StudyRecord

_CACHE: dict[str, Path] = {}


def write_manifest(case_dir: Path, status: str = "done") -> None:
    """The two fields analysis checks, as the runner writes them (status, scene_hash)."""
    scene = json.loads((case_dir / "scene.json").read_text())
    (case_dir / "manifest.json").write_text(json.dumps(
        {"case_id": scene["case_id"], "status": status, "scene_hash": scene["scene_hash"],
         "reason": "" if status == "done" else "test: marked " + status}))


def wet_study(engine, tmp_path_factory) -> Path:
    """Study folder: cg3-weber-r0 (run), cg3-weber-r1 (its copy as a replica), both done,
    and cg3-bond-r0 rendered with a ``failed`` manifest and no dumps."""
    if "study" in _CACHE:
        return _CACHE["study"]
    out = tmp_path_factory.mktemp("wetstudy")
    wf = load_workflow(DRUM, ["sweep.cg_levels=[3]", "sweep.rules=[weber,bond]",
                              "scene.process.run_time=0.2", "scene.process.settle_time=0.05"])
    rendered = render_workflow(wf)
    write_study(wf, rendered, out, out / "meshes")
    case = out / "cg3-weber-r0"
    proc = run_liggghts(engine, case, nprocs=2, timeout=300)
    assert proc.returncode == 0, proc.stdout[-3000:]
    write_manifest(case)
    write_manifest(out / "cg3-bond-r0", "failed")
    rep = out / "cg3-weber-r1"
    shutil.copytree(case, rep)
    scene = json.loads((rep / "scene.json").read_text())
    scene["case_id"], scene["replica"] = "cg3-weber-r1", 1
    (rep / "scene.json").write_text(json.dumps(sealed(scene)))    # as if ligwf wrote it
    write_manifest(rep)
    study = StudyRecord.read(out)
    replica = CaseEntry(2, "cg3-weber-r1", 3.0, "weber", 1, scene["scene_hash"])
    dataclasses.replace(study, cases=study.cases + (replica,)).write(out)
    _CACHE["study"] = out
    return out


def wet_case_frames(engine, tmp_path_factory):
    """(case folder, run facts, [(particles, contacts)] of every frame) of the run case of
    :func:`wet_study` (``cg3-weber-r0``), the frames read afresh for each caller."""
    from ligwf.analysis.frames.dumps import discover_frames, read_contacts, read_particles
    from ligwf.analysis.granules.case import RunFacts
    from ligwf.study.case import CaseFolder

    case = CaseFolder.open(wet_study(engine, tmp_path_factory) / "cg3-weber-r0")
    facts = RunFacts.of_case(case)
    frames = [(read_particles(f.particles, dt=facts.dt), read_contacts(f.contacts))
              for f in discover_frames(case.path)]
    return case, facts, frames
