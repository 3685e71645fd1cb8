"""A case folder as one typed object: its identity, its scaled scene, its manifest.

:meth:`CaseFolder.open` parses the case's scene record once (the scaled scene becomes a
:class:`~ligwf.scene.scaling.ScaledScene`); every stage -- runner, resume, analysis, flow,
report, stability report -- asks the object instead of reading files. The manifest is
read fresh on every call (the runner rewrites it while a case runs).
"""

from __future__ import annotations

import json
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from ligwf.engine.health import DONE
from ligwf.errors import ConfigError
from ligwf.scene.scaling import ScaledScene
from ligwf.study.layout import MANIFEST_FILE, SCENE_FILE, SCREEN_FILE, THERMO_FILE
from ligwf.study.manifest import Manifest, read_manifest, write_manifest


def group_of(varied: dict[str, Any]) -> str:
    """The sweep group of a case: its swept scene values as canonical JSON (cases of one
    group are compared with the CG1 cases of the same group)."""
    return json.dumps(varied, sort_keys=True)


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

    @classmethod
    def open(cls, path: Path | str) -> "CaseFolder":
        """Parse the case's scene record; ConfigError when it is missing or invalid."""
        path = Path(path)
        try:
            rec = json.loads((path / SCENE_FILE).read_text())
            return cls(path=path, case_id=rec["case_id"], index=int(rec["index"]),
                       cg=float(rec["cg"]), rule=str(rec["rule"]),
                       replica=int(rec.get("replica", 0)),
                       group=group_of(rec.get("varied", {})),
                       scaled=ScaledScene.from_dict(rec["scaled"]), scene_hash=rec["scene_hash"],
                       explicit_dt=(rec.get("scene", {}).get("numerics", {}) or {})
                       .get("dt") is not None)
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise ConfigError(f"{path}: not a readable case folder (scene record missing or "
                              f"invalid: {exc})") from None

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

    def write_manifest(self, manifest: Manifest) -> None:
        write_manifest(self.path, manifest)

    # ----------------------------------------------------------------- usability
    def why_not_usable(self) -> str | None:
        """Why later stages may not use this case (None: its manifest says done and was
        written for the scene the folder holds now)."""
        if not (self.path / MANIFEST_FILE).is_file():
            return "no manifest (the case was not run by `ligwf run`)"
        m = self.manifest()
        if m is None:
            return "unreadable manifest"
        if m.status != DONE:
            return f"manifest status {m.status!r}" + (f": {m.reason}" if m.reason else "")
        if m.scene_hash != self.scene_hash:
            return "manifest scene hash differs from the case's scene (re-rendered since the run)"
        return None

    def usable(self) -> bool:
        return self.why_not_usable() is None

    # ----------------------------------------------------------------- time line
    @property
    def production_start_step(self) -> int:
        """Step at which the drum starts turning (after the fill waves and settling)."""
        return self.scaled.insertion_steps + self.scaled.settle_steps

    def steady_start_step(self, steady_after: float) -> float:
        """First step of the steady window: ``steady_after`` of the production time is the
        start-up and left out (flow metrics and GSD use the same window)."""
        return self.production_start_step + steady_after * self.scaled.run_steps

    def drum_angle(self, step: int) -> float:
        """Angle (rad) the drum has turned by at ``step`` (it turns during production)."""
        s = self.scaled
        return s.omega * max(0, step - self.production_start_step) * s.dt
