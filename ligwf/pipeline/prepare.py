"""Prepare a study: validate, scale, render, pre-flight (all in memory), then write.

:func:`prepare_workflow` (a workflow file and its ``--set`` overrides) / :func:`prepare`
(a loaded workflow) is the first step of every path that starts from a workflow (``check``,
``render``, ``run``, ``study``, ``slurm submit``): every case is scaled and rendered and
the stability pre-flight runs before anything is written, so a bad value or an unsafe case
is refused with nothing half-done. :func:`write` (:func:`write_study`) then writes the
study record (the workflow, its analysis settings, the case list) and one folder per case
with the input, the drum mesh (from the mesh cache), the scene record (original and scaled
parameters plus a content hash) and the empty output folders the input writes into (names:
:mod:`ligwf.study.layout`). Every file is written atomically.

The content hash covers the scaled parameters, the rendered input and the mesh, so a
runner can tell whether a finished case still matches what the workflow asks for.
"""

from __future__ import annotations

import os
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable, Sequence

from ligwf import __version__
from ligwf.errors import ConfigError
from ligwf.fsio import (NOT_WRITABLE, atomic_write_bytes, atomic_write_json, atomic_write_text,
                        not_writable)
from ligwf.engine.mesh import cache_problem, cached_mesh, drum_stl, scene_sag
from ligwf.engine.plan import CaseLoad, case_load
from ligwf.engine.render import render
from ligwf.scene.scaled import ScaledScene
from ligwf.scene.regime import definition_warning, regime_warnings
from ligwf.scene.stability import Preflight, check_rendered
from ligwf.scene.window import held_window_warnings
from ligwf.scene.renamed import renamed_setting_warnings
from ligwf.scene.unused import unused_setting_warnings
from ligwf.scene.workflow import Case, Workflow, comparison_warnings, load_workflow
from ligwf.study.case import content_hash
from ligwf.study.layout import MESH_CACHE_DIR, MESH_NAME, OUTPUT_DIRS, SCENE_FILE
from ligwf.study.made_from import sealed
from ligwf.study.ownership import check_own_folder
from ligwf.study.study import Study
from ligwf.study.study_record import CaseEntry, StudyRecord


def default_mesh_cache() -> Path:
    """Mesh cache folder: $LIGWF_MESH_CACHE, else meshes/ under the current folder."""
    return Path(os.environ.get("LIGWF_MESH_CACHE", MESH_CACHE_DIR))


@dataclass(frozen=True)
class RenderedCase:
    """A case with its scaled scene, rendered files and content hash (nothing written)."""

    case: Case
    scaled: ScaledScene
    files: dict[str, str]
    mesh_text: str
    scene_hash: str

    def scene_record(self) -> dict:
        """The case's scene record, sealed (:func:`ligwf.study.made_from.sealed`)."""
        return sealed({
            "ligwf_version": __version__,
            "case_id": self.case.case_id,
            "index": self.case.index,
            "cg": self.case.cg,
            "rule": self.scaled.rule,
            "replica": self.case.replica,
            "varied": {k: v for k, v in self.case.varied},
            "scene": self.case.scene.model_dump(mode="json"),
            "scaled": self.scaled.to_dict(),
            "scene_hash": self.scene_hash,
        })


#: most steps LIGGGHTS runs in one ``run`` command ("Invalid run command N value" above)
ENGINE_MAX_RUN_STEPS = 2**31 - 1


def check_run_lengths(case: Case, scaled: ScaledScene) -> None:
    """Refuse a phase longer than one LIGGGHTS ``run`` command takes: the engine would stop
    with "Invalid run command N value" after the fill (a tiny dt with a long run)."""
    fall = "the fill's insertion wave (the fall across the drum)"
    for field, steps in (("process.settle_time", scaled.numerics.settle_steps),
                         ("process.run_time", scaled.numerics.run_steps),
                         (fall, scaled.fill.wave_steps)):
        if steps > ENGINE_MAX_RUN_STEPS:
            seconds = steps * scaled.numerics.dt
            most = ENGINE_MAX_RUN_STEPS * scaled.numerics.dt
            shown = f"{field} = {seconds:g} s" if field != fall else f"{field}, {seconds:.3g} s,"
            raise ConfigError(f"case {case.case_id}: {shown} is {steps:,} steps of dt = "
                              f"{scaled.numerics.dt:.3g} s; LIGGGHTS runs at most "
                              f"{ENGINE_MAX_RUN_STEPS:,} steps in one run command (allowed "
                              f"range (0, {most:.3g}] s at this dt; or raise numerics.dt / "
                              "numerics.dt_rayleigh_fraction)")


def render_case(case: Case, template_dirs: Iterable[str | Path] = ()) -> RenderedCase:
    """Scale and render one case in memory."""
    scaled = case.scaled()
    check_run_lengths(case, scaled)
    files = render(scaled, template_dirs)
    mesh_text = drum_stl(case.scene.drum, scene_sag(case.scene))
    return RenderedCase(case, scaled, files, mesh_text, content_hash(scaled, files, mesh_text))


def render_workflow(wf: Workflow, template_dirs: Iterable[str | Path] = ()) -> list[RenderedCase]:
    """Render every case in memory: all errors surface before any file is written."""
    dirs = tuple(template_dirs)
    return [render_case(c, dirs) for c in wf.cases]


@dataclass(frozen=True)
class Prepared:
    """A validated workflow, every case rendered, and the pre-flight verdicts."""

    workflow: Workflow
    rendered: list[RenderedCase]
    preflight: list[Preflight]
    warnings: list[str]          # marginal findings (and refusals let through)


def prepare(wf: Workflow, template_dirs: Iterable[str | Path] = (),
            allow_unstable: bool = False) -> Prepared:
    """Render every case and pre-flight it; raises UnstableCase on a refusal unless
    ``allow_unstable``. Writes nothing."""
    rendered = render_workflow(wf, template_dirs)
    reports, warnings = check_rendered(rendered, allow_unstable)
    return Prepared(wf, rendered, reports,
                    renamed_setting_warnings(wf) + warnings + regime_warnings(rendered)
                    + comparison_warnings(wf)
                    + unused_setting_warnings(wf)
                    + held_window_warnings(wf)
                    + definition_warning(wf.analysis, rendered))


def write_case(rc: RenderedCase, out_dir: Path, mesh_cache: Path | None = None) -> Path:
    """Write one rendered case folder under ``out_dir``; returns the folder."""
    case_dir = Path(out_dir) / rc.case.case_id
    case_dir.mkdir(parents=True, exist_ok=True)
    for sub in OUTPUT_DIRS:
        (case_dir / sub).mkdir(exist_ok=True)
    mesh_src = cached_mesh(rc.case.scene.drum, scene_sag(rc.case.scene),
                          mesh_cache or default_mesh_cache())
    # a per-process temporary name: two `ligwf run` may write one study at once
    atomic_write_bytes(case_dir / MESH_NAME, Path(mesh_src).read_bytes())
    for name, text in rc.files.items():
        atomic_write_text(case_dir / name, text)
    atomic_write_json(case_dir / SCENE_FILE, rc.scene_record())
    return case_dir


def write_study(wf: Workflow, rendered: list[RenderedCase], out_dir: Path,
                mesh_cache: Path | None = None, replace: bool = False) -> Study:
    """Write every case folder, then the study record; returns the written study.
    First, before anything is written (:func:`ligwf.study.ownership.check_own_folder`):
    ConfigError when ``out_dir`` holds another study (unless ``replace``) or a path to
    write is a symbolic link or resolves outside ``out_dir``. FolderNotWritable (one line
    naming the folder) on a full or read-only file system."""
    out_dir = Path(out_dir)
    files = {MESH_NAME, *(name for rc in rendered for name in rc.files)}
    check_own_folder(out_dir, wf.name, wf.raw, [rc.case.case_id for rc in rendered], files,
                     replace)
    try:
        out_dir.mkdir(parents=True, exist_ok=True)
        for rc in rendered:
            write_case(rc, out_dir, mesh_cache)
    except OSError as exc:
        if exc.errno in NOT_WRITABLE:
            raise not_writable(exc, out_dir) from exc
        raise
    StudyRecord(wf.name, wf.raw, wf.analysis.model_dump(mode="json"),
                wf.accept.model_dump(mode="json"),
                tuple(CaseEntry(rc.case.index, rc.case.case_id, rc.case.cg, rc.scaled.rule,
                                rc.case.replica, rc.scene_hash) for rc in rendered),
                wf.description, __version__).write(out_dir)
    return Study.open(out_dir)


def prepare_workflow(workflow: Path, overrides: Sequence[str] = (),
                     template_dirs: Iterable[Path] = (), allow_unstable: bool = False) -> Prepared:
    """Load and validate a workflow, render every case in memory and pre-flight it
    (UnstableCase on a refusal unless ``allow_unstable``). Writes nothing."""
    return prepare(load_workflow(workflow, list(overrides)), tuple(template_dirs),
                   allow_unstable)


def write(prepared: Prepared, out: Path, mesh_cache: Path | None = None,
          replace: bool = False) -> Study:
    """Write the prepared study folder (identical cases are rewritten byte for byte, so
    their outputs stay and a re-run resumes); ``replace``: also over another study."""
    return write_study(prepared.workflow, prepared.rendered, out, mesh_cache, replace)


def mesh_cache_lines(prepared: Prepared, mesh_cache: Path | None = None) -> list[str]:
    """A line for each damaged drum mesh in the mesh cache the prepared cases will use
    (:func:`ligwf.engine.mesh.cache_problem`; writing repairs it). Reads only."""
    cache = mesh_cache or default_mesh_cache()
    geometries = {(rc.case.scene.drum, scene_sag(rc.case.scene)) for rc in prepared.rendered}
    return [why for drum, sag in geometries if (why := cache_problem(drum, sag, cache))]


def prepared_loads(prepared: Prepared) -> list[CaseLoad]:
    """The planner's view of every prepared case (named as its case folder will be)."""
    return [case_load(rc.case.case_id, rc.scaled) for rc in prepared.rendered]
