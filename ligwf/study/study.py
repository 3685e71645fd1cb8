"""A study folder as one object: its name, its analysis settings and error budget, its
cases in order.

:meth:`Study.open` takes a study folder (with its study record) or a single case folder
(a foreign case run by hand: one case, default analysis settings). Every command that
works on a rendered study -- ``run-case``, ``status``, ``analyse``, ``report``, the Slurm
status and resubmit -- lists cases through it, in case-index order.
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path

from ligwf.errors import ConfigError
from ligwf.study.case import CaseFolder
from ligwf.study.layout import ANALYSIS_DIR, REPORT_DIR, is_case_folder, is_study_folder
from ligwf.study.study_record import StudyRecord
from ligwf.scene.accept import AcceptSettings, build_accept_settings
from ligwf.scene.settings import AnalysisSettings, build_analysis_settings


@dataclass(frozen=True)
class Study:
    """A rendered study (or a single case folder seen as a one-case study)."""

    path: Path
    name: str
    analysis: AnalysisSettings
    case_ids: tuple[str, ...]          # in case-index order
    single_case: bool = False
    #: the workflow's ``accept:`` block (the defaults for a case folder or an older study)
    accept: AcceptSettings = AcceptSettings()

    @classmethod
    def open(cls, path: Path | str) -> "Study":
        """Open a study folder or a case folder; ConfigError when it is neither."""
        path = Path(path)
        if is_study_folder(path):
            rec = StudyRecord.read(path)
            return cls(path, rec.name, build_analysis_settings(rec.analysis, "study analysis"),
                       rec.case_ids, accept=build_accept_settings(rec.accept, "study accept"))
        if is_case_folder(path):
            case = CaseFolder.open(path)
            return cls(path, case.case_id, AnalysisSettings(), (case.case_id,), True)
        raise ConfigError(f"{path} is not a ligwf study folder (nor a case folder): render "
                          "or submit a workflow first")

    @staticmethod
    def workflow_of(path: Path | str) -> dict:
        """The workflow (raw mapping, ``--set`` overrides applied) a study folder was
        written from; ConfigError when the folder has none."""
        raw = StudyRecord.read(path).workflow
        if not raw:
            raise ConfigError(f"{path}: its study record holds no workflow")
        return raw

    # ----------------------------------------------------------------- cases
    @property
    def case_dirs(self) -> list[Path]:
        """Case folders in case-index order (they may not all exist)."""
        if self.single_case:
            return [self.path]
        return [self.path / cid for cid in self.case_ids]

    @cached_property
    def cases(self) -> tuple[CaseFolder, ...]:
        """Every case, opened (ConfigError when one is missing or broken)."""
        return tuple(CaseFolder.open(d) for d in self.case_dirs)

    def case(self, index: int) -> CaseFolder:
        """Case number ``index`` (its position in case-index order)."""
        if not 0 <= index < len(self.case_ids):
            raise ConfigError(f"case index {index}: the study has cases 0..{len(self.case_ids) - 1}")
        return CaseFolder.open(self.case_dirs[index])

    def usable_cases(self, require_manifest: bool = True) -> tuple[list[CaseFolder], list[dict]]:
        """Cases later stages may use, in order, and the others as ``{case_id, reason}``."""
        usable, skipped = [], []
        for d in self.case_dirs:
            try:
                case = CaseFolder.open(d)
            except ConfigError as exc:
                skipped.append({"case_id": d.name, "reason": str(exc)})
                continue
            problem = case.why_not_usable() if require_manifest else case.record_problem()
            if problem:
                skipped.append({"case_id": case.case_id, "reason": problem})
            else:
                usable.append(case)
        return usable, skipped

    # ----------------------------------------------------------------- outputs
    @property
    def analysis_dir(self) -> Path:
        return self.path / ANALYSIS_DIR

    @property
    def report_dir(self) -> Path:
        return self.path / REPORT_DIR


def studies_below(root: Path) -> list[Study]:
    """``root`` itself when it is a study or case folder, else every study folder directly
    below it (a stress suite: one study per variant), sorted by name."""
    root = Path(root)
    if is_study_folder(root) or is_case_folder(root):
        return [Study.open(root)]
    if not root.is_dir():
        return []
    return [Study.open(p) for p in sorted(root.iterdir()) if is_study_folder(p)]
