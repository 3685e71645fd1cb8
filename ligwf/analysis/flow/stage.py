"""Flow stage of the analysis: per usable case its steady window and flow metrics.

Run by :func:`ligwf.analysis.runner.analyse` (``ligwf analyse``) once per case, before
the granule tables are written: the steady window found here is the one the GSD, the
kinetics, the controls and the report use (computed once, from one read of the
production frames). Only the steady part of the production phase counts: frames from the
study's ``steady_after`` on (a fraction of the production time,
:meth:`ligwf.study.case.CaseFolder.steady_start_step`; or ``auto``: from the bed's
measured spin-up, :mod:`ligwf.analysis.flow.steady`, on every production frame). Frames are
checked as the granule analysis checks them (:mod:`ligwf.analysis.frames.checks`:
expected steps, dump record, particle count, ids, radii, drum); refused and missing ones
are listed per case with their reasons, never used. Every series registered in
:mod:`ligwf.analysis.flow.registry` is evaluated on every checked production frame.

Outputs (staged with the granule tables, names in :mod:`ligwf.study.layout`): the flow
table (one row per case: steady window, the :class:`~ligwf.analysis.flow.frame.FlowSummary`
scalars and the value of every registered metric) and the flow record
(:class:`~ligwf.analysis.records.flow.FlowRecord`).
"""

from __future__ import annotations

import os
from dataclasses import asdict, dataclass, field, replace

import numpy as np
import pandas as pd

from ligwf.analysis.flow import registry as flow_metrics
from ligwf.analysis.frames.dumps import read_particles
from ligwf.analysis.flow.frame import DrumGeometry, frame_flow, summarise, velocity_field
from ligwf.analysis.frames.checks import ExpectedFrames, check_particles, plan_frames
from ligwf.analysis.frames.loop import FrameAnalysis
from ligwf.analysis.records.flow import CaseFlow, FlowRecord
from ligwf.analysis.flow.steady import auto_fraction, is_auto
from ligwf.analysis.flow.fields import case_fields, kernel_width
from ligwf.analysis.flow.spreading import spread_series
from ligwf.analysis.records.fields import (CRITERION_KERNELS, CaseFields, fields_bytes,
                                           image_text)
from ligwf.scene.settings import AnalysisSettings
from ligwf.errors import ConfigError, DumpReadError
from ligwf.study import layout
from ligwf.study.case import CaseFolder

#: the default kernel width of the cross-section fields, CG1 diameters
FIELD_KERNEL = AnalysisSettings.model_fields["field_kernel"].default


def steady_fraction(case: CaseFolder, steady_after, flows: list) -> float:
    """The steady window as a fraction of production: the fixed setting, or for ``auto``
    the measured spin-up of the flow angle and the kinetic energy (``flows`` are the
    production frames' :class:`~ligwf.analysis.flow.frame.FrameFlow`)."""
    if not is_auto(steady_after):
        return float(steady_after)
    dt = case.scaled.numerics.dt
    return auto_fraction(np.array([f.time for f in flows]),
                         [np.array([f.angle_of_repose for f in flows]),
                          np.array([f.kinetic_energy for f in flows])],
                         case.production_start_step * dt, case.scaled.numerics.run_steps * dt)


@dataclass
class FlowFrames(FrameAnalysis):
    """The flow metrics' pass over a case's production frames (a
    :class:`~ligwf.analysis.frames.loop.FrameAnalysis`): each frame checked against its run
    (dump record, particles), its flow (:func:`~ligwf.analysis.flow.frame.frame_flow`) and
    registered series; ``results``: (frame, files, flow, series) of the usable frames,
    ``problems``: ``{"step", "reason"}`` of the frames refused, missing or broken."""

    case: CaseFolder
    plan: ExpectedFrames
    strip: float | None = None      # m, the study's surface strips (surface.study_strip)
    results: list = field(default_factory=list)
    problems: list[dict] = field(default_factory=list)

    def _prepare(self, frames) -> list:
        self.results = []
        self._geo = DrumGeometry.from_scaled(self.case.scaled, self.strip)
        production = self.case.production_start_step
        self.problems = [p for p in self.plan.problems if p["step"] >= production]
        return [ff for ff in (self.plan.frames if frames is None else frames)
                if ff.step >= production]

    def _single_frame(self, ff):
        try:
            self.plan.check_record(ff)
            frame = read_particles(ff.particles, ff.step, self.case.scaled.numerics.dt)
            check_particles(self.case, frame)
        except DumpReadError as exc:
            self.problems.append({"step": ff.step, "reason": str(exc)})
            return None
        try:
            flow = frame_flow(frame, self._geo)
            values = flow_metrics.frame_series(frame, self._geo, flow)
        except (MemoryError, KeyboardInterrupt):
            raise
        except Exception as exc:   # a frame that passed its checks and still breaks a metric
            self.problems.append({"step": ff.step, "reason": f"{ff.particles}: flow metrics "
                                  f"failed on this frame ({type(exc).__name__}: {exc})"})
            return None
        return frame, ff, flow, values

    def _conclude(self) -> None:
        self.results = [r for r in self.results if r is not None]


def _production_frames(case: CaseFolder, plan, strip: float | None = None
                       ) -> tuple[list, list, list, list[dict]]:
    """Checked particle frames of the production phase, their flows, their registered
    series, and the frames refused or missing (``{"step", "reason"}``)."""
    done = FlowFrames(case, plan, strip).run()
    return ([(frame, ff) for frame, ff, _, _ in done.results],
            [flow for _, _, flow, _ in done.results],
            [values for *_, values in done.results], done.problems)


def _listed(v) -> list | float:
    return [float(x) for x in np.ravel(v)] if np.ndim(v) else float(v)


def case_flow(case: CaseFolder, steady_after, field_kernel: float = FIELD_KERNEL,
              strip: float | None = None) -> tuple[CaseFlow, list[str]]:
    """The flow of one case folder and its skipped-frame notes (the steady window's); the
    record is ``measured`` only when a frame of the window was usable (else the one note
    says why), and then carries the window's cross-section fields (kernel width
    ``field_kernel`` CG1 diameters, :mod:`ligwf.analysis.flow.fields`). ConfigError when
    its dump record is unreadable. ``strip``: the angle's surface strips in m, the study's
    one resolution (None: twice the case's own diameter)."""
    plan = plan_frames(case)
    frames, all_flows, all_series, problems = _production_frames(case, plan, strip)
    fraction = steady_fraction(case, steady_after, all_flows)
    first = case.steady_start_step(fraction)
    rel = {ff.step: os.path.relpath(ff.particles, case.path) for ff in plan.frames}
    head = dict(case_id=case.case_id, cg=case.cg, rule=case.rule, replica=case.replica,
                group=case.group, steady_fraction=fraction, steady_from_step=first,
                frames=tuple(sorted(rel.items())),
                snapshot=(frames[-1][1].step, rel[frames[-1][1].step]) if frames else None,
                read_steps=tuple(ff.step for _, ff in frames))
    skipped = [p["reason"] for p in problems if p["step"] >= first]
    steady = [k for k, (f, _) in enumerate(frames) if f.step >= first]
    if not steady:
        return CaseFlow(**head), [
            f"{case.path}: no readable particle dump in the steady part (steps >= "
            f"{first:.0f})" + (f"; first refused: {problems[-1]['reason']}" if problems else "")]
    geo = DrumGeometry.from_scaled(case.scaled, strip)
    steady_frames = [frames[k][0] for k in steady]
    fields = case_fields(steady_frames, geo, kernel_width(geo, case.cg, field_kernel),
                         case.scaled.drum.length,
                         {k: head[k] for k in ("case_id", "cg", "rule", "replica", "group")},
                         tuple(sorted({*CRITERION_KERNELS, float(field_kernel)})))
    flow = measured_flow(head, steady_frames, all_flows, all_series, steady, geo, fields)
    spread = spread_series([f for f, _ in frames],
                           float(case.scaled.liquid_values.wet_sphere_content or 0.0),
                           case.scaled.drum.rotation_period)
    if spread is not None:
        flow = replace(flow, spreading={k: list(v) if isinstance(v, tuple) else v
                                        for k, v in asdict(spread).items()})
    return flow, skipped


def measured_flow(head: dict, steady_frames: list, flows: list, series: list[dict],
                  steady: list[int], geo: DrumGeometry, fields: CaseFields | None = None
                  ) -> CaseFlow:
    """The :class:`CaseFlow` of a case (``head``: its identity and window fields) from its
    production frames' flows and registered series, ``steady`` indexing the window's
    frames (``steady_frames`` their particle frames, for the velocity field), with the
    window's cross-section ``fields``."""
    window = [flows[k] for k in steady]
    summ = summarise(window)
    cu, cv, mu, mv = velocity_field(steady_frames, geo)
    kept = {name: [_listed(series[k][name]) for k in steady] for name in flow_metrics.SERIES}
    values = {m.name: m.value(kept[m.series])
              for m in flow_metrics.METRICS.values() if not m.is_error}
    return CaseFlow(
        **head, values=values, series=kept, times=[f.time for f in window],
        profile_s=summ.profile_s, profile_v_mean=summ.profile_v_mean,
        profile_v_std=summ.profile_v_std, field_u=cu.tolist(), field_v=cv.tolist(),
        field_vel_u=mu.tolist(), field_vel_v=mv.tolist(),
        production_times=[f.time for f in flows],
        production_angles=[f.angle_of_repose for f in flows],
        production_kinetic=[f.kinetic_energy for f in flows],
        summary=summ.scalars(), fields=fields)


def flow_cases(cases: list[CaseFolder], steady_after, field_kernel: float = FIELD_KERNEL,
               strip: float | None = None) -> tuple[dict[str, CaseFlow], dict[str, list[str]]]:
    """(flow per case, skipped-frame notes per case) of ``cases`` (``strip``: the study's
    surface strips, m); a case whose dump record is unreadable is left out with its reason
    as the note."""
    out, notes = {}, {}
    for c in cases:
        try:
            flow, skipped = case_flow(c, steady_after, field_kernel, strip)
        except ConfigError as exc:
            notes[c.case_id] = [str(exc)]
            continue
        out[c.case_id] = flow
        if skipped:
            notes[c.case_id] = skipped
    return out, notes


def flow_record(flows: dict[str, CaseFlow], notes: dict[str, list[str]], steady_after,
                skipped_cases: list[dict]) -> FlowRecord:
    """The flow record of a study's cases (with the specifications of the registered
    metrics)."""
    return FlowRecord(steady_after=steady_after,
                      metrics=tuple(flow_metrics.METRICS.values()), cases=dict(flows),
                      skipped_frames=dict(notes), skipped_cases=list(skipped_cases))


def flow_table(record: FlowRecord) -> pd.DataFrame:
    """One row per measured case: identity, steady window, the flow summary's scalars and
    every registered metric's value not already among them."""
    rows = []
    for c in record.measured():
        row = {"case_id": c.case_id, "cg": c.cg, "rule": c.rule, "replica": c.replica,
               "group": c.group, "steady_fraction": c.steady_fraction,
               "steady_from_step": c.steady_from_step, **c.summary}
        for name, v in c.values.items():
            row.setdefault(name, v)
        rows.append(row)
    return pd.DataFrame(rows)


def field_files(record: FlowRecord) -> dict[str, bytes]:
    """The analysis files of the cross-section fields: the archive of every measured
    case's (``layout.FIELDS_DATA``, what the report reads) and per case its ParaView
    image of the window means; empty without any."""
    cases = [c.fields for c in record.measured() if c.fields is not None]
    if not cases:
        return {}
    out = {layout.FIELDS_DATA: fields_bytes(cases)}
    for c in cases:
        out[layout.field_image(c.case_id)] = image_text(c).encode()
    return out
