"""A case folder as one typed object: its identity, its scaled scene, its manifest.

:meth:`CaseFolder.open` parses the case's scene record once (the scaled scene becomes a
:class:`~ligwf.scene.scaled.ScaledScene`); every stage -- runner, resume, analysis, flow,
report, stability report -- asks the object instead of reading files. The manifest is
read fresh on every call (the runner rewrites it while a case runs).

The case also knows what its run must have left behind, so the analysis can tell a
complete, untouched run from a damaged one: the dump steps (:meth:`CaseFolder.expected_dump_steps`,
from the scene's dump interval and the steps the manifest says were run), and the dump
record written with every ``done`` manifest (size and SHA-256 of each file in ``post/``,
:meth:`CaseFolder.dump_record`), which identifies the run's own dumps: a frame deleted,
edited, copied in from another replica or added afterwards no longer matches it.
"""

from __future__ import annotations

import hashlib
import os
import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ligwf.errors import ConfigError
from ligwf.fsio import atomic_write_json, file_sha256
from ligwf.scene.model import Scene
from ligwf.scene.scaled import ScaledScene
from ligwf.scene.scaling import scale
from ligwf.scene.workflow import CONTROL_KEY
from ligwf.study.extension import extension_steps
from ligwf.study.condition import Condition
from ligwf.study.group import SweepGroup
from ligwf.study.layout import (ANALYSED_DUMP_RE, DUMP_RECORD, INPUT_NAME, MANIFEST_FILE, MESH_NAME,
                                POST_DIR, SCENE_FILE, SCREEN_FILE, THERMO_FILE)
from ligwf.study.made_from import edit_summary, record_edits
from ligwf.study.manifest import DONE, Manifest, read_manifest, write_manifest
from ligwf.study.paths import check_case_id
from ligwf.study.thermo_table import rows_from_csv, table_problem




def file_identity(path: Path) -> tuple[int, int, int] | None:
    """(inode, size, modification time ns) of a file, None when it cannot be read: a file
    with the same identity is taken to hold the same bytes it was hashed with."""
    try:
        st = os.stat(path)
    except OSError:
        return None
    return st.st_ino, st.st_size, st.st_mtime_ns


@dataclass(frozen=True)
class KnownDigests:
    """SHA-256 of files hashed earlier (by the running case's dump hasher,
    :mod:`ligwf.engine.dump_hasher`), each with the file's identity then (inode, size,
    modification time ns): a digest is used only for a file that still has that identity,
    any other file is hashed now."""

    files: dict[str, tuple[tuple[int, int, int], str]]

    def digest(self, path: Path) -> str:
        known = self.files.get(path.name)
        if known is not None and known[0] == file_identity(path):
            return known[1]
        return file_sha256(path)


NO_DIGESTS = KnownDigests({})


@dataclass(frozen=True)
class DumpRecord:
    """The files a finished run left in ``post/``: name -> (size in bytes, SHA-256)."""

    scene_hash: str
    steps_done: int
    files: dict[str, tuple[int, str]]

    def mismatch(self, path: Path) -> str | None:
        """Why ``path`` is not the file the run left (None: same size and digest)."""
        entry = self.files.get(path.name)
        if entry is None:
            return f"{path}: not among the dumps the run left (dump record {DUMP_RECORD})"
        if not path.is_file():
            return f"{path}: the run left it, it is gone now (deleted or moved?)"
        size = path.stat().st_size
        if size != entry[0]:
            return f"{path}: {size} bytes, the run left {entry[0]} (truncated or replaced)"
        if file_sha256(path) != entry[1]:
            return (f"{path}: content differs from the dump the run left (SHA-256 mismatch: "
                    "edited, corrupted or copied from another run)")
        return None


def content_hash(scaled: ScaledScene, files: dict[str, str], mesh_text: str) -> str:
    """sha256 over the scaled parameters, the rendered files and the mesh (the scene hash
    rendering stores in the scene record and the runner in the manifest)."""
    h = hashlib.sha256()
    h.update(json.dumps(scaled.to_dict(), sort_keys=True).encode())
    for name in sorted(files):
        h.update(name.encode() + b"\0" + files[name].encode() + b"\0")
    h.update(hashlib.sha256(mesh_text.encode()).digest())
    return h.hexdigest()


def recomputed_hash(path: Path, scaled: ScaledScene) -> str | None:
    """The content hash of a case folder as rendering computed it (scaled parameters,
    input, mesh: :func:`content_hash`), from what the folder holds now;
    None when its input or mesh is missing (a case folder put together by hand)."""
    try:
        files = {INPUT_NAME: (path / INPUT_NAME).read_text()}
        mesh = (path / MESH_NAME).read_text()
    except (OSError, UnicodeDecodeError):
        return None
    return content_hash(scaled, files, mesh)


def _changed_fields(rec: dict, scaled: ScaledScene) -> list[str]:
    """Scaled fields that do not follow from the record's own scene, CG level and rule
    (``field = stored (expected ...)``); empty when that cannot be worked out."""
    changed = [f"{key} = {rec[key]!r} (scaled.{key} = {getattr(scaled, key)!r})"
               for key in ("cg", "rule") if str(rec[key]) != str(getattr(scaled, key))
               and not (key == "cg" and float(rec[key]) == scaled.cg)]
    try:
        expected = scale(Scene.model_validate(rec["scene"]), scaled.cg, scaled.rule,
                         scaled.replica).to_dict()
    except Exception:                    # an edited scene that no longer validates
        return changed or ["scene (no longer a valid scene)"]
    stored = scaled.to_dict()
    return changed + [f"scaled.{k} = {stored[k]!r} (its scene gives {expected[k]!r})"
                      for k in stored if k in expected and stored[k] != expected[k]]


def scene_record_problem(path: Path, rec: dict, scaled: ScaledScene,
                         check_hash: bool = True) -> str | None:
    """Why a case folder's scene record is not the one rendering wrote (None: its stored
    content hash is recomputed and matches, its CG level and rule are the scaled scene's,
    and its original scene block, scaled again, gives exactly its scaled values), naming
    the changed fields where they can be told. The content hash covers the scaled values,
    the input and the mesh, not the original block: an original edited after rendering
    (a surface tension multiplied by 10) is caught by scaling it again. With
    ``check_hash`` False the hash is not recomputed: an input or mesh edited by hand is
    no problem then (the runner launches an edited input and lets the engine's verdict
    judge it), only the record's own fields are checked."""
    if str(rec["rule"]) != scaled.rule or float(rec["cg"]) != scaled.cg:
        return "changed: " + "; ".join(_changed_fields(rec, scaled))
    digest = recomputed_hash(path, scaled) if check_hash else None
    if digest is None or digest == rec["scene_hash"]:
        if fields := _changed_fields(rec, scaled):
            return ("its original scene block no longer gives its scaled values (changed: "
                    + "; ".join(fields) + ")")
        return None
    fields = _changed_fields(rec, scaled)
    what = ("changed: " + "; ".join(fields)) if fields else (
        f"the scaled parameters, {INPUT_NAME} or {MESH_NAME} differ from what was rendered")
    return f"content hash recomputed on read differs from the stored scene_hash ({what})"


def folder_fingerprint(path: Path) -> dict:
    """What identifies a case folder's results: the stored scene hash and the SHA-256 of
    its dump record (None where missing or unreadable); an analysis records it per case."""
    try:
        scene = json.loads((path / SCENE_FILE).read_text()).get("scene_hash")
    except (OSError, ValueError, AttributeError):
        scene = None
    record = path / DUMP_RECORD
    return {"scene_hash": scene, "dump_record": _analysed_digest(record) if record.is_file() else None}


def _analysed_digest(record: Path) -> str:
    """SHA-256 over the record's entries of the dumps an analysis reads (the whole file's
    digest when it is unreadable, so a damaged record still differs)."""
    try:
        files = json.loads(record.read_text())["files"]
        kept = {k: v for k, v in files.items() if ANALYSED_DUMP_RE.match(k)}
    except (OSError, ValueError, KeyError, TypeError, AttributeError):
        return file_sha256(record)
    return hashlib.sha256(json.dumps(kept, sort_keys=True).encode()).hexdigest()


def granules_absent(scaled: ScaledScene) -> str | None:
    """Why a case's run holds no granule data, in words (None: it dumped its contacts)."""
    if not scaled.wet:
        return (f"dry scene (liquid.model: {scaled.liquid_values.model}): no liquid bridges hold "
                "particles together, so there are no granules to analyse")
    if not scaled.contact_dumps:
        return ("scene.analysis.contact_dumps: false: the runs write no contact dumps (set it "
                "to true to analyse granules and their size distribution)")
    return None


def group_of(varied: dict[str, Any]) -> str:
    """The sweep group of a case: its swept scene values as canonical JSON (cases of one
    group are compared with the CG1 cases of the same group; :class:`SweepGroup`)."""
    return SweepGroup.of(varied).text


def group_label(group: str) -> str:
    """The sweep group as a reader names it (:attr:`ligwf.study.group.SweepGroup.label`):
    ``all cases``, ``key=value``, ``cohesionless control, key=value``; text that is not a
    group record is returned as it is."""
    return SweepGroup.parse(group).label


@dataclass(frozen=True)
class CaseFolder:
    """One rendered case folder (see :mod:`ligwf.study.layout`)."""

    path: Path
    case_id: str
    index: int
    cg: float
    rule: str
    replica: int
    group: str                 # see :func:`group_of`
    scaled: ScaledScene
    scene_hash: str
    explicit_dt: bool          # the scene fixed dt (the pre-flight judges it differently)
    #: production steps added to the rendered run (:data:`EXTENSION_FILE`): ``scaled``
    #: includes them, :attr:`rendered_scaled` is the scene as rendered and hashed
    extension_steps: int = 0

    @classmethod
    def open(cls, path: Path | str) -> "CaseFolder":
        """Parse the case's scene record (and its production extension, if any);
        ConfigError when it is missing or invalid."""
        path = Path(path)
        try:
            rec = json.loads((path / SCENE_FILE).read_text())
            check_case_id(rec["case_id"], str(path / SCENE_FILE))
            scaled = ScaledScene.from_dict(rec["scaled"])
            added = extension_steps(path, scaled)
            if added:
                scaled = scaled.with_run_steps(scaled.numerics.run_steps + added)
            return cls(path=path, case_id=rec["case_id"], index=int(rec["index"]),
                       cg=float(rec["cg"]), rule=str(rec["rule"]),
                       replica=int(rec.get("replica", 0)),
                       group=group_of(rec.get("varied", {})),
                       scaled=scaled, scene_hash=rec["scene_hash"],
                       explicit_dt=(rec.get("scene", {}).get("numerics", {}) or {})
                       .get("dt") is not None, extension_steps=added)
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise ConfigError(f"{path}: not a readable case folder (scene record missing or "
                              f"invalid: {exc})") from None

    @property
    def condition(self) -> Condition:
        """The condition this case is a replica of (its sweep group, CG level and rule)."""
        return Condition.of(self)

    @property
    def sweep_group(self) -> SweepGroup:
        """The case's sweep group as a value (:attr:`group` is its canonical JSON)."""
        return self.condition.sweep_group

    @property
    def rendered_scaled(self) -> ScaledScene:
        """The scaled scene as rendered (without a production extension): what the scene
        record and its content hash describe."""
        if not self.extension_steps:
            return self.scaled
        return self.scaled.with_run_steps(self.scaled.numerics.run_steps - self.extension_steps)

    # ----------------------------------------------------------------- files of the run
    @property
    def screen(self) -> Path:
        """Screen capture of the current attempt."""
        return self.path / SCREEN_FILE

    @property
    def thermo(self) -> Path:
        """Thermo table over all attempts."""
        return self.path / THERMO_FILE

    def manifest(self) -> Manifest | None:
        """The runner's manifest now (None: not run, or unreadable)."""
        return read_manifest(self.path)

    def write_manifest(self, manifest: Manifest, digests: KnownDigests = NO_DIGESTS) -> None:
        """Write the manifest; a ``done`` one after the dump record of the run's ``post/``
        (so a done case always identifies its dumps), any other removes a stale record.
        ``digests``: files hashed while the case ran (used where the file is unchanged)."""
        record = self.path / DUMP_RECORD
        if manifest.status == DONE:
            post = self.path / POST_DIR
            files = ({p.name: [p.stat().st_size, digests.digest(p)]
                      for p in sorted(post.iterdir()) if p.is_file()} if post.is_dir() else {})
            atomic_write_json(record, {"scene_hash": manifest.scene_hash,
                                       "steps_done": manifest.steps_done, "files": files})
        else:
            record.unlink(missing_ok=True)
        write_manifest(self.path, manifest)

    def dump_record(self) -> DumpRecord | None:
        """The dump record of the finished run (None: none was written, e.g. a case run by
        hand); ConfigError when it is unreadable."""
        path = self.path / DUMP_RECORD
        if not path.is_file():
            return None
        try:
            rec = json.loads(path.read_text())
            files = {str(k): (int(v[0]), str(v[1])) for k, v in rec["files"].items()}
            return DumpRecord(str(rec["scene_hash"]), int(rec["steps_done"]), files)
        except (OSError, ValueError, KeyError, TypeError, IndexError, AttributeError) as exc:
            raise ConfigError(f"{path}: unreadable dump record ({type(exc).__name__}: {exc})") from None

    def expected_dump_steps(self, end_step: int) -> list[int]:
        """Steps at which the engine writes a frame up to ``end_step``: the multiples of the
        dump interval from the start of production on (the dumps are defined when the drum
        starts turning; LIGGGHTS writes on multiples of the interval only)."""
        every = self.scaled.numerics.dump_every
        first = -(-self.production_start_step // every) * every
        return list(range(first, min(end_step, self.scaled.total_steps) + 1, every))

    def thermo_problem(self, manifest: Manifest) -> str | None:
        """Why the thermo table disagrees with a runner's manifest (None: it ends at the
        manifest's last step with the scene's particle count, or the manifest is a
        hand-written one without a step count)."""
        if manifest.steps_done <= 0:
            return None
        try:
            rows = rows_from_csv(self.thermo.read_text())
        except FileNotFoundError:
            return f"{self.thermo.name} is missing (the runner writes it for every run)"
        except (OSError, ValueError, KeyError, TypeError) as exc:
            return f"{self.thermo.name} is unreadable (truncated or corrupt?): {exc}"
        last = rows[-1].step if rows else None
        if (why := table_problem(rows, self.scaled.numerics.thermo_every,
                                 self.scaled.particles.count)) is not None:
            return f"{self.thermo.name}: {why}"
        if last != manifest.steps_done:
            return (f"{self.thermo.name} ends at step {last}, the manifest says "
                    f"{manifest.steps_done} steps were run (truncated or replaced)")
        return None

    # ----------------------------------------------------------------- usability
    def record_problem(self, check_hash: bool = True) -> str | None:
        """Why the scene record is not the one rendering wrote (None: its content hash,
        recomputed from the scaled parameters, input and mesh in the folder, matches the
        stored one, and its CG level and rule are the scaled scene's). Asked by every stage
        that uses a case's results, not by the runner (an engine run of an edited input
        ends in its own verdict)."""
        try:
            rec = json.loads((self.path / SCENE_FILE).read_text())
        except (OSError, ValueError) as exc:
            return f"{SCENE_FILE} unreadable: {exc}"
        why = scene_record_problem(self.path, rec, self.rendered_scaled, check_hash)
        if edited := record_edits(rec):       # the seal names the field edited by hand
            why = f"edited after ligwf wrote it ({edit_summary(edited)})" + (f"; {why}" if why else "")
        return (None if why is None else f"{SCENE_FILE}: {why}; the record no longer describes "
                "the run (edited after rendering?): render and run the case again")

    def why_not_usable(self) -> str | None:
        """Why later stages may not use this case (None: its scene record is the rendered
        one, its manifest says done and was written for the scene the folder holds now)."""
        if (why := self.record_problem()) is not None:
            return why
        if not (self.path / MANIFEST_FILE).is_file():
            return "no manifest (the case was not run by `ligwf run`)"
        try:
            m = self.manifest()
        except (ValueError, TypeError, AttributeError):   # valid JSON of the wrong shape
            m = None
        if m is None:
            return "unreadable manifest (truncated or corrupt)"
        if m.status != DONE:
            return f"manifest status {m.status!r}" + (f": {m.reason}" if m.reason else "")
        if m.scene_hash != self.scene_hash:
            return "manifest scene hash differs from the case's scene (re-rendered since the run)"
        return self.thermo_problem(m)

    def usable(self) -> bool:
        return self.why_not_usable() is None

    # ----------------------------------------------------------------- time line
    @property
    def production_start_step(self) -> int:
        """Step at which the drum starts turning (after the fill waves and settling)."""
        return self.scaled.insertion_steps + self.scaled.numerics.settle_steps

    def steady_start_step(self, steady_after: float) -> float:
        """First step of the steady window: ``steady_after`` of the production time is the
        start-up and left out (flow metrics and GSD use the same window)."""
        return self.production_start_step + steady_after * self.scaled.numerics.run_steps

    def drum_angle(self, step: int) -> float:
        """Angle (rad) the drum has turned by at ``step`` (it turns during production)."""
        s = self.scaled
        return s.drum.omega * max(0, step - self.production_start_step) * s.numerics.dt
