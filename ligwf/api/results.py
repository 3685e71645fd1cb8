"""A study's results as one object (:class:`StudyResults`, made by :func:`open_study`).

Tables are read on first use through :mod:`ligwf.api.tables` and cached; every access
returns a copy. Plots go through :mod:`ligwf.api.plots` (the report's figure functions).
"""

from __future__ import annotations

from dataclasses import dataclass
from functools import cached_property
from pathlib import Path
from typing import TYPE_CHECKING, Any

import pandas as pd

from ligwf.analysis.records.analysis_record import AnalysisRecord
from ligwf.analysis.records.fields import CaseFields, read_fields
from ligwf.analysis.records.flow import FlowRecord
from ligwf.api import fields, plots
from ligwf.api.tables import (ANALYSE, REPORT, TABLES, MissingOutput, TableSpec,
                              read_checked, typed)
from ligwf.errors import ConfigError, LigwfError
from ligwf.report import dictionary
from ligwf.report.digests import damaged_report_files
from ligwf.report.problems import Problems, study_problems
from ligwf.inference.verdict import Verdict
from ligwf.report.write import checked_analysis
from ligwf.inference.verdict_records import read_verdict
from ligwf.scene.accept import AcceptSettings
from ligwf.scene.settings import AnalysisSettings
from ligwf.study import layout
from ligwf.study.study import Study
from ligwf.study.study_record import StudyRecord

if TYPE_CHECKING:
    from matplotlib.axes import Axes

_BY_NAME = {t.attribute: t for t in TABLES}


def open_study(path: str | Path) -> "StudyResults":
    """A study folder's results (:class:`StudyResults`); ConfigError (one line) when
    ``path`` is no study folder. Nothing is read until a table is asked for."""
    if not isinstance(path, (str, Path)) or not str(path).strip():
        raise ConfigError(f"open_study: path = {path!r}: a study folder (a str or "
                          "pathlib.Path naming it)")
    study = Study.open(Path(path))
    if study.single_case:
        raise ConfigError(f"{path}: a case folder, not a study: open the study folder above "
                          "it (ligwf.analysis.foreign analyses dumps run by hand)")
    return StudyResults(study)


@dataclass(frozen=True)
class StudyResults:
    """What a study measured: its tables (pandas, typed as :mod:`ligwf.api` says),
    its workflow and analysis settings, the paths of its report; plots that take and
    return a matplotlib Axes. Make one with :func:`open_study`."""

    study: Study

    # ------------------------------------------------------------- identity and settings
    @property
    def path(self) -> Path:
        """The study folder."""
        return self.study.path

    @property
    def name(self) -> str:
        return self.study.name

    @property
    def settings(self) -> AnalysisSettings:
        """The study's ``analysis:`` settings (what the analysis ran with)."""
        return self.study.analysis

    @property
    def accept(self) -> AcceptSettings:
        """The study's ``accept:`` block: the error budget the verdict decides against."""
        return self.study.accept

    @cached_property
    def record(self) -> StudyRecord:
        """The study record (``study.json``): name, workflow, analysis settings, cases."""
        return StudyRecord.read(self.path)

    @property
    def workflow(self) -> dict[str, Any]:
        """The workflow the study was rendered from (scene, sweep, analysis, as validated)."""
        return dict(self.record.workflow)

    @property
    def case_ids(self) -> tuple[str, ...]:
        """Every case of the study in case-index order (usable or not)."""
        return self.study.case_ids

    # ------------------------------------------------------------- paths
    @property
    def analysis_dir(self) -> Path:
        return self.study.analysis_dir

    @property
    def report_dir(self) -> Path:
        return self.study.report_dir

    @property
    def summary(self) -> Path:
        """The report's markdown page (MissingOutput before ``ligwf report``)."""
        return self._file(layout.REPORT_DIR, layout.SUMMARY_REPORT, REPORT, "report page")

    @property
    def html(self) -> Path:
        """The report's HTML page (MissingOutput before ``ligwf report``)."""
        return self._file(layout.REPORT_DIR, layout.HTML_REPORT, REPORT, "report page")

    @property
    def paraview(self) -> dict[str, Path]:
        """case id -> its ParaView collection (particles + turning drum) in the report;
        only the cases the report wrote one for."""
        folder = self.report_dir / layout.PARAVIEW_DIR
        found = {cid: folder / layout.paraview_collection(cid) for cid in self.case_ids}
        return {cid: p for cid, p in found.items() if p.is_file()}

    @property
    def figures(self) -> dict[str, Path]:
        """file name -> path of every figure the report wrote."""
        folder = self.report_dir / layout.FIGURES_DIR
        if not folder.is_dir():
            return {}
        return {p.name: p for p in sorted(folder.glob(layout.FIGURE_GLOB))}

    # ------------------------------------------------------------- tables
    @property
    def cases(self) -> pd.DataFrame:
        """One row per usable case: run facts, costs, metrics, errors against CG1."""
        return self.table("cases")

    @property
    def conditions(self) -> pd.DataFrame:
        """One row per (sweep group, CG level, rule); per metric ``m``: ``m``, ``m_lo``,
        ``m_hi``, ``m_se``; errors also ``m_floor``, ``m_floor_source``, ``m_vs_floor``."""
        return self.table("conditions")

    @property
    def verdict(self) -> pd.DataFrame:
        """The verdict: per sweep group, CG level, rule and criterion of the ``accept:``
        block its ``state`` (pass / fail / undecided), ``value`` [``lo``, ``hi``] against the
        ``budget``, the speedup; ``cheapest`` marks the condition the sentence names."""
        return self.table("verdict")

    @cached_property
    def verdict_result(self) -> Verdict:
        """The verdict as typed objects (``ligwf.inference.verdict.Verdict``): per group its
        conditions and criteria and the sentence naming the cheapest level that meets the
        whole budget (``groups[i].sentence``, ``groups[i].cheapest``)."""
        found = read_verdict(self.report_dir)
        if found is None:
            raise MissingOutput(f"{self.report_dir / layout.VERDICT_RECORD}: no verdict yet: "
                                f"run `{REPORT} {self.path}`")
        return found

    @property
    def extrapolation(self) -> pd.DataFrame:
        """CG1 from CG-n levels: per sweep group, rule and signed criterion with two or
        more CG-n levels, the CG1 value extrapolated from them with its 95 % interval
        beside the measured CG1 mean."""
        return self.table("extrapolation")

    @property
    def spreading(self) -> pd.DataFrame:
        """Placed liquid's spreading rate per CG-n level against CG1 (no rows without
        placed liquid)."""
        return self.table("spreading")

    @property
    def noise_floor(self) -> pd.DataFrame:
        """Per sweep group and metric the CG1 value and its CG1-vs-CG1 scatter."""
        return self.table("noise_floor")

    @property
    def flow(self) -> pd.DataFrame:
        """Per case its steady window and flow metrics."""
        return self.table("flow")

    @property
    def frames(self) -> pd.DataFrame:
        """Per case and frame: status, reason, particles, contacts, bonds, granules."""
        return self.table("frames")

    @property
    def granules(self) -> pd.DataFrame:
        """Per granule and frame: members, volume [m^3], centre of mass [m]."""
        return self.table("granules")

    @property
    def gsd(self) -> pd.DataFrame:
        """Per condition and volume bin the steady-window GSD with bootstrap bands."""
        return self.table("gsd")

    @property
    def gsd_summary(self) -> pd.DataFrame:
        return self.table("gsd_summary")

    @property
    def gsd_pooling(self) -> pd.DataFrame:
        return self.table("gsd_pooling")

    @property
    def gsd_pooling_summary(self) -> pd.DataFrame:
        return self.table("gsd_pooling_summary")

    @property
    def kinetics(self) -> pd.DataFrame:
        """Per case and frame: granule count, d10 / d50 / d90 [m], largest granule."""
        return self.table("kinetics")

    @property
    def kinetics_summary(self) -> pd.DataFrame:
        return self.table("kinetics_summary")

    @property
    def sensitivity(self) -> pd.DataFrame:
        """Granule count, d50 and largest granule under each variant of the definition."""
        return self.table("sensitivity")

    @property
    def controls(self) -> pd.DataFrame:
        """Each wet case beside its cohesionless twin, per granule definition."""
        return self.table("controls")

    def table(self, name: str) -> pd.DataFrame:
        """The table called ``name`` (an attribute of :data:`TABLES`), as a copy."""
        return self._read(name).copy()

    def describe(self, name: str) -> pd.DataFrame:
        """The columns of the table ``name`` as the data dictionary documents them
        (``docs/data_dictionary.md``, :mod:`ligwf.report.dictionary`): ``column``,
        ``dtype``, ``unit`` (as stored, SI), ``label`` and ``meaning`` (empty for a
        column the dictionary does not know)."""
        table, file = self._read(name), _BY_NAME[name].file
        rows = []
        for col, dtype in table.dtypes.items():
            entry = dictionary.column(str(col), file)
            rows.append({"column": col, "dtype": str(dtype),
                         **{k: getattr(entry, k) if entry else "" for k in
                            ("unit", "label", "meaning")}})
        return typed(pd.DataFrame(rows, columns=["column", "dtype", "unit", "label", "meaning"]))

    def tables(self) -> dict[str, pd.DataFrame]:
        """Every table the study has now, by name (copies; the missing ones left out)."""
        return {name: self.table(name) for name, there in self.available().items() if there}

    def available(self) -> dict[str, bool]:
        """table name -> whether the study has it now (nothing is read)."""
        return {t.attribute: self._path(t).is_file() for t in TABLES}

    @cached_property
    def flow_record(self) -> FlowRecord:
        """The flow record of the analysis: per case its steady window, per-frame metric
        series, velocity profile (``ligwf.analysis.records.flow``)."""
        path = self._file(layout.ANALYSIS_DIR, layout.FLOW_PROFILES, ANALYSE, "flow record")
        try:
            return FlowRecord.read(path)
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise MissingOutput(f"{path}: unreadable flow record ({type(exc).__name__}): run "
                                f"`{ANALYSE} {self.path}` again") from None

    @cached_property
    def field_record(self) -> dict[str, CaseFields]:
        """case id -> its coarse-grained cross-section fields (per steady frame kernel sums
        on the grid: ``ligwf.analysis.records.fields``)."""
        path = self._file(layout.ANALYSIS_DIR, layout.FIELDS_DATA, ANALYSE, "flow fields")
        try:
            return read_fields(path)
        except (OSError, ValueError, KeyError, TypeError) as exc:
            raise MissingOutput(f"{path}: unreadable flow fields ({type(exc).__name__}): run "
                                f"`{ANALYSE} {self.path}` again") from None

    @property
    def fields(self) -> pd.DataFrame:
        """Per case and cross-section grid node the steady-window mean fields: ``u``,
        ``v`` [m], ``solid_fraction``, ``velocity_u``, ``velocity_v``, ``speed`` [m/s],
        ``temperature`` [m^2/s^2] (:func:`ligwf.api.fields.fields_table`)."""
        return fields.fields_table(self.field_record)

    @property
    def field_null_check(self) -> pd.DataFrame:
        """Each cohesionless twin's field error against the wet CG1 case, beside the floor."""
        return self.table("field_null_check")

    @property
    def field_images(self) -> dict[str, Path]:
        """case id -> its window-mean fields as VTK ImageData (opens in ParaView)."""
        found = {cid: self.analysis_dir / layout.field_image(cid) for cid in self.case_ids}
        return {cid: p for cid, p in found.items() if p.is_file()}

    @property
    def profiles(self) -> pd.DataFrame:
        """Per measured case and depth bin: the mean downhill velocity [m/s] (and its std)
        against the normalised depth below the free surface (``depth``: 0 at the surface,
        1 at the bed's bottom), from the flow record."""
        rows = [{"case_id": c.case_id, "cg": c.cg, "rule": c.rule, "replica": c.replica,
                 "depth": s, "v_mean": v, "v_std": sd}
                for c in self.flow_record.measured()
                for s, v, sd in zip(c.profile_s, c.profile_v_mean, c.profile_v_std)]
        frame = pd.DataFrame(rows, columns=["case_id", "cg", "rule", "replica", "depth",
                                            "v_mean", "v_std"])
        return typed(frame.astype({"cg": float, "replica": int, "depth": float,
                                   "v_mean": float, "v_std": float}))

    def check(self) -> Problems:
        """Refuse (one line, a LigwfError) what ``ligwf report`` would refuse: analysis
        outputs missing or no longer matching the study (re-run or re-rendered cases,
        changed settings, an edited table, dumps changed since: this hashes the dumps), a
        report older than the analysis it was built from, and report files changed since
        the report wrote them (their SHA-256 against the report's digest record). Returns
        what the report lists as not used (skipped or unlisted cases, frames, outputs:
        :func:`ligwf.report.problems.study_problems`). The tables are read without this
        check; call it when the study may have changed since."""
        checked_analysis(self.study)
        record = self.analysis_dir / layout.ANALYSIS_RECORD
        report = self.report_dir / layout.CONDITIONS_REPORT
        if report.is_file() and report.stat().st_mtime < record.stat().st_mtime:
            raise MissingOutput(f"{self.report_dir}: older than the analysis in "
                                f"{self.analysis_dir}: run `{REPORT} {self.path}` again")
        if self.report_dir.is_dir() and (damaged := damaged_report_files(self.report_dir)):
            more = f" (and {len(damaged) - 1} more)" if len(damaged) > 1 else ""
            raise MissingOutput(f"{damaged[0]}{more}: run `{REPORT} {self.path}` again")
        return study_problems(self.study)

    # ------------------------------------------------------------- plots
    def plot_pareto(self, ax: Axes | None = None, metric: str = "angle_error") -> Axes:
        """One error of every CG-n condition against its production cost (core-s per
        simulated s per 1,000 original particles, the speedup's footing), with its 95 %
        interval and the CG1 noise floor: the report's error-vs-run-time panel. ``metric``:
        an error column of :attr:`conditions` (``angle_error``, ``profile_error``, ...)."""
        conditions = self._read("conditions")
        if metric not in conditions:
            errors = [c[: -len("_vs_floor")] for c in conditions if c.endswith("_vs_floor")]
            raise LigwfError(f"plot_pareto: metric = {metric!r} is not an error of this "
                             f"study's conditions table (one of {', '.join(errors)})")
        return plots.error_vs_cost(ax, conditions, metric, self.flow_record)

    def plot_run_cost(self, ax: Axes | None = None) -> Axes:
        """Fill, settle and production core-seconds of every condition."""
        return plots.run_cost(ax, self._read("conditions"))

    def plot_gsd(self, ax: Axes | None = None) -> Axes:
        """The volume-weighted GSD of every condition (steady window, bootstrap bands),
        against the equivalent diameter, with each CG level's located size limit."""
        return plots.gsd(ax, self._read("gsd"), self.settings.gsd_volume, self.analysis_dir)

    def plot_profiles(self, ax: Axes | None = None) -> Axes:
        """The velocity profile of every case against the depth below the free surface."""
        return plots.profiles(ax, self._read("cases"), self.flow_record)

    def plot_kinetics(self, ax: Axes | None = None, quantity: str = "d50") -> Axes:
        """One granule-kinetics quantity per condition (``granules``, ``d50``,
        ``largest_granule``, ``granule_share``) against the time from production start,
        with its band over replicas."""
        starts = {c.case_id: c.production_start_step * c.scaled.numerics.dt
                  for c in self.study.usable_cases()[0]}
        return plots.kinetics(ax, self._read("kinetics_summary"), self._read("kinetics"),
                              quantity, starts)

    def plot_field(self, case_id: str, ax: Axes | None = None,
                   quantity: str = "speed") -> Axes:
        """One steady-window field of one case on the drum cross-section (``quantity``:
        ``solid_fraction``, ``velocity_u``, ``velocity_v``, ``speed`` with arrows,
        ``temperature``)."""
        record = self.field_record
        if case_id not in record:
            raise LigwfError(f"plot_field: case_id = {case_id!r} has no fields (the cases "
                             f"with fields: {', '.join(record)})")
        return fields.plot_field(ax, record[case_id], quantity)

    # ------------------------------------------------------------- reading
    def _path(self, spec: TableSpec) -> Path:
        return self.path / spec.folder / spec.file

    def _file(self, folder: str, file: str, command: str, what: str) -> Path:
        path = self.path / folder / file
        if not path.is_file():
            raise MissingOutput(f"{path}: no {what} yet: run `{command} {self.path}`"
                                + (" (or `ligwf study`, which does)" if command != REPORT
                                   else ""))
        return path

    def _read(self, name: str) -> pd.DataFrame:
        cache = self.__dict__.setdefault("_tables", {})
        if name not in cache:
            spec = _BY_NAME.get(name)
            if spec is None:
                raise LigwfError(f"no table {name!r}: the tables are {', '.join(_BY_NAME)}")
            path = self._path(spec)
            if not path.is_file() and spec.granules:
                if (why := self._why_no_granules()) is not None:
                    raise MissingOutput(f"{self.path}: no {name} table: {why}")
            path = self._file(spec.folder, spec.file, spec.command, f"{name} table")
            cache[name] = read_checked(path, spec, self.path)
        return cache[name]

    def _why_no_granules(self) -> str | None:
        """Why the analysis wrote no granule tables, from its record (None: no such
        reason recorded, the tables are simply missing)."""
        record = AnalysisRecord.read(self.analysis_dir)
        absent = record.granules_absent if record is not None else ()
        if not absent:
            return None
        reasons = sorted({str(a.get("reason", "")) for a in absent})
        return "no granule data by design (" + "; ".join(reasons) + ")"
