"""The flow metrics of the report, registered in one place.

A flow metric is one function of a frame plus one registration line::

    def bed_height(frame, geo, flow):      # ParticleFrame, DrumGeometry, FrameFlow -> float
        return float(frame.positions[:, 2].max())

    register(MetricSpec("bed_height", "bed height [m]", "bed_height", MEAN, POSITIVE,
                        unit="m", meaning="height of the highest particle centre"),
             bed_height)

(``unit`` and ``meaning``: its entry in the data dictionary, which lists every registered
metric in the flow, case and condition tables.)

The analysis stage evaluates every registered series on every production frame that
passed its checks, keeps the steady window's values per case in the flow record with the
metric's specification (:mod:`ligwf.analysis.records`), and the report shows every metric
of the record in its case and condition tables with its interval (and, for an error
statistic, against the CG1 noise floor) -- nothing else to edit. The function gets the
frame's built-in flow quantities (``flow``, :class:`~ligwf.analysis.flow.frame.FrameFlow`: the
surface fit, profile, ...) so it need not fit the surface again. A metric may instead
summarise a series already registered (no function: angle std from ``angle``), and an
error statistic compares a series' mean with the CG1 cases' (angle and profile errors).
"""

from __future__ import annotations

from typing import Callable

import numpy as np

from ligwf.analysis.frames.dumps import ParticleFrame
from ligwf.analysis.flow.frame import RIGID_FRAME_SHARE, DrumGeometry, FrameFlow
from ligwf.analysis.records import statistics as st
from ligwf.analysis.records.metrics import CASE_TABLE, POSITIVE, UNIT, MetricSpec

FrameSeries = Callable[[ParticleFrame, DrumGeometry, FrameFlow], "float | np.ndarray"]

#: series name -> per-frame function
SERIES: dict[str, FrameSeries] = {}
#: metric name -> specification, in report order
METRICS: dict[str, MetricSpec] = {}


def register(spec: MetricSpec, per_frame: FrameSeries | None = None) -> MetricSpec:
    """Add a metric (and, with ``per_frame``, its series ``spec.series``)."""
    if spec.name in METRICS:
        raise ValueError(f"flow metric {spec.name!r} is already registered")
    if per_frame is not None:
        if spec.series in SERIES and SERIES[spec.series] is not per_frame:
            raise ValueError(f"series {spec.series!r} is already registered")
        SERIES[spec.series] = per_frame
    elif spec.series not in SERIES:
        raise ValueError(f"flow metric {spec.name!r}: no series {spec.series!r} registered "
                         "(give its per-frame function)")
    METRICS[spec.name] = spec
    return spec


def unregister(name: str) -> None:
    """Remove a metric (and its series when no other metric uses it)."""
    spec = METRICS.pop(name)
    if all(m.series != spec.series for m in METRICS.values()):
        SERIES.pop(spec.series, None)


def frame_series(frame: ParticleFrame, geo: DrumGeometry, flow: FrameFlow) -> dict:
    """Every registered series of one frame."""
    return {name: fn(frame, geo, flow) for name, fn in SERIES.items()}


def _angle(frame, geo, flow):
    return flow.angle_of_repose


def _rigid(frame, geo, flow):
    return flow.rigid_fraction


def _rms(frame, geo, flow):
    return flow.rms_speed


def _flowing_layer(frame, geo, flow):
    return flow.flowing_layer_thickness


def _profile(frame, geo, flow):
    return flow.profile_v


register(MetricSpec("angle_of_repose", "angle [deg]", "angle", st.MEAN, (-90.0, 90.0),
                    unit="deg", meaning=(
        "dynamic angle of repose of the free surface (signed: positive rising towards the wall "
        "that moves up): of a case, the mean of its steady frames' angles (frames where a surface"
        " was fitted); of a condition, the mean over its replicas")), _angle)
register(MetricSpec("angle_of_repose_std", "angle std [deg]", "angle", st.STD, POSITIVE,
                    tables=(CASE_TABLE,), unit="deg", meaning=(
        "standard deviation of the angle of repose over the steady frames")))
register(MetricSpec("angle_error", "angle err", "angle", st.RELATIVE_ERROR, POSITIVE,
                    unit="1", meaning=(
        "relative error of the angle of repose against the group's CG1 mean, |a - a1| / a1")))
register(MetricSpec("profile_error", "profile err (L2)", "profile", st.RELATIVE_L2, POSITIVE,
                    condition_label="profile err", unit="1", meaning=(
        "relative L2 error of the velocity profile along the normalised depth against the group's"
        " CG1 profile")), _profile)
register(MetricSpec("rigid_frame_share", "rigid frames", "rigid", st.SHARE_ABOVE, UNIT,
                    threshold=RIGID_FRAME_SHARE, unit="1", meaning=(
        "share of steady frames in which most of the bed turns with the drum as a rigid block")),
         _rigid)
register(MetricSpec("rms_speed_rel_fluctuation", "rms speed fluctuation", "rms",
                    st.RELATIVE_FLUCTUATION, POSITIVE, tables=(),
                    unit="1", meaning=(
        "relative fluctuation (std / mean) of the rms speed over the steady frames")), _rms)
register(MetricSpec("flowing_layer_thickness_mean", "flowing layer [m]", "flowing_layer",
                    st.MEAN, POSITIVE, tables=(), unit="m", shown="mm", meaning=(
        "mass-equivalent thickness of the flowing layer (the grains above the depth where the "
        "velocity profile changes sign, over the packing of the bed below it: no fitted surface "
        "in it, so the same layer reads the same at every grain size), mean over the steady "
        "window")),
         _flowing_layer)
