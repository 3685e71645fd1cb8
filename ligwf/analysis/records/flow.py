"""The flow record: what the analysis stage measured of the flow, per case, for the report.

Written once by ``ligwf analyse`` (:mod:`ligwf.analysis.flow.stage`) into the analysis
folder (``layout.FLOW_PROFILES``, with the flow table ``layout.FLOW_TABLE`` beside it) and
listed with its digest in the analysis record. Per case: its steady window (the one the
GSD, kinetics and controls used), the specifications of the metrics
(:class:`~ligwf.analysis.records.metrics.MetricSpec`), each metric's per-case value and
the per-frame series of the steady window they come from (what the report's
block-bootstrap intervals resample), the velocity profile and field, the production
series the automatic window was found on, and the frames it read (for ParaView and the
snapshots). The report reads it through :meth:`FlowRecord.read`.
"""

from __future__ import annotations

import json
import math
from dataclasses import dataclass, field
from pathlib import Path

from ligwf.analysis.records.fields import CaseFields
from ligwf.analysis.records.metrics import MetricSpec
from ligwf.analysis.records.renamed import RENAMED
from ligwf.study import layout


def _nums(values) -> list:
    """JSON-safe numbers (nan / inf -> None), nested lists kept."""
    out = []
    for v in values:
        if isinstance(v, (list, tuple)):
            out.append(_nums(v))
        elif v is None or not math.isfinite(float(v)):
            out.append(None)
        else:
            out.append(float(v))
    return out


@dataclass(frozen=True)
class CaseFlow:
    """The flow of one case: its steady window always; the rest when a frame of the
    window was usable (``measured``)."""

    case_id: str
    cg: float
    rule: str
    replica: int
    group: str
    steady_fraction: float            # of the production time left out
    steady_from_step: int             # first step of the steady window
    frames: tuple[tuple[int, str], ...] = ()   # every planned frame: (step, particle dump
    #                                            relative to the case folder)
    snapshot: tuple[int, str] | None = None    # the last checked frame (step, dump)
    read_steps: tuple[int, ...] = ()           # production frames read and checked
    values: dict[str, float] = field(default_factory=dict)   # metric -> per-case value
    series: dict[str, list] = field(default_factory=dict)    # series -> per steady frame
    times: list[float] = field(default_factory=list)          # s, the steady frames
    profile_s: list[float] = field(default_factory=list)      # normalised depth of the bins
    profile_v_mean: list = field(default_factory=list)        # m/s, mean downhill velocity
    profile_v_std: list = field(default_factory=list)
    field_u: list[float] = field(default_factory=list)        # m, cell centres
    field_v: list[float] = field(default_factory=list)
    field_vel_u: list = field(default_factory=list)           # m/s, (cells, cells)
    field_vel_v: list = field(default_factory=list)
    production_times: list[float] = field(default_factory=list)
    production_angles: list = field(default_factory=list)
    production_kinetic: list = field(default_factory=list)
    #: placed liquid only (:mod:`ligwf.analysis.flow.spreading`): revolutions,
    #: dry_content_share, dry_wet_share per production frame, dry_particles, particles
    spreading: dict = field(default_factory=dict)
    summary: dict[str, float] = field(default_factory=dict)   # the flow table's scalars
    #: the cross-section fields of the steady window (written to their own archive by the
    #: analysis, :mod:`ligwf.analysis.records.fields`; not part of this record's JSON)
    fields: CaseFields | None = field(default=None, repr=False, compare=False)

    @property
    def measured(self) -> bool:
        return bool(self.times)

    def to_json(self) -> dict:
        d = dict(self.__dict__)
        d.pop("fields", None)
        d["frames"] = [list(f) for f in self.frames]
        d["snapshot"] = list(self.snapshot) if self.snapshot else None
        d["read_steps"] = list(self.read_steps)
        d["values"] = {k: (None if not math.isfinite(v) else v) for k, v in self.values.items()}
        d["summary"] = {k: (v if not isinstance(v, float) or math.isfinite(v) else None)
                        for k, v in self.summary.items()}
        d["series"] = {k: _nums(v) for k, v in self.series.items()}
        for k in ("profile_v_mean", "profile_v_std", "field_vel_u", "field_vel_v",
                  "production_angles", "production_kinetic"):
            d[k] = _nums(d[k])
        d["spreading"] = {k: _nums(v) if isinstance(v, (list, tuple)) else v
                          for k, v in self.spreading.items()}
        return d

    @classmethod
    def from_json(cls, d: dict) -> "CaseFlow":
        nan = math.nan
        return cls(**{**d, "frames": tuple((int(s), str(p)) for s, p in d.get("frames", [])),
                      "snapshot": tuple(d["snapshot"]) if d.get("snapshot") else None,
                      "read_steps": tuple(int(s) for s in d.get("read_steps", ())),
                      "values": {k: nan if v is None else float(v)
                                 for k, v in d.get("values", {}).items()},
                      # a record of the previous release: its summary keys as now
                      "summary": {RENAMED[layout.FLOW_TABLE].get(k, k): nan if v is None else v
                                  for k, v in d.get("summary", {}).items()}})


@dataclass(frozen=True)
class FlowRecord:
    """The flow of a study's usable cases (see the module docstring)."""

    steady_after: float | str
    metrics: tuple[MetricSpec, ...]
    cases: dict[str, CaseFlow]
    skipped_frames: dict[str, list[str]] = field(default_factory=dict)  # case -> reasons
    skipped_cases: list[dict] = field(default_factory=list)            # {case_id, reason}

    @property
    def steady_auto(self) -> bool:
        return self.steady_after == "auto"

    def metric(self, name: str) -> MetricSpec:
        return next(m for m in self.metrics if m.name == name)

    @property
    def frame_metrics(self) -> tuple[MetricSpec, ...]:
        """The metrics with a per-case value (not errors against CG1)."""
        return tuple(m for m in self.metrics if not m.is_error)

    @property
    def error_metrics(self) -> tuple[MetricSpec, ...]:
        return tuple(m for m in self.metrics if m.is_error)

    def measured(self) -> list[CaseFlow]:
        """The cases with a usable frame in their steady window, in record order."""
        return [c for c in self.cases.values() if c.measured]

    def to_text(self) -> str:
        return json.dumps({"steady_after": self.steady_after,
                           "metrics": [m.to_json() for m in self.metrics],
                           "cases": {k: c.to_json() for k, c in self.cases.items()},
                           "skipped_frames": self.skipped_frames,
                           "skipped_cases": self.skipped_cases}, indent=1) + "\n"

    @classmethod
    def from_json(cls, d: dict) -> "FlowRecord":
        return cls(steady_after=d["steady_after"],
                   metrics=tuple(MetricSpec.from_json(m) for m in d["metrics"]),
                   cases={k: CaseFlow.from_json(c) for k, c in d["cases"].items()},
                   skipped_frames=d.get("skipped_frames", {}),
                   skipped_cases=d.get("skipped_cases", []))

    @classmethod
    def read(cls, path: Path) -> "FlowRecord":
        """The record at ``path``; OSError / ValueError / KeyError when missing or not one."""
        return cls.from_json(json.loads(Path(path).read_text()))
