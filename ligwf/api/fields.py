"""The flow fields of a study for the API: the cross-section maps of the steady window.

The analysis keeps per case and steady frame the kernel sums of the coarse-grained fields
(:mod:`ligwf.analysis.records.fields`); the API gives their window mean as one long table
(:func:`fields_table`: a row per case and grid node) and draws one field of one case with
the report's map function (:func:`plot_field`).
"""

from __future__ import annotations

import numpy as np
import pandas as pd
from matplotlib.axes import Axes

from ligwf.inference.field_errors import MATERIAL_SOLID
from ligwf.analysis.records.fields import FIELD_UNITS, CaseFields, fields_of
from ligwf.api.plots import axes
from ligwf.api.tables import typed
from ligwf.errors import LigwfError
from ligwf.report.field_figures import field_map

#: colour map of each field on a map
CMAPS = {"solid_fraction": "cividis", "velocity_u": "RdBu_r", "velocity_v": "RdBu_r",
         "speed": "viridis", "temperature": "magma"}


def fields_table(cases: dict[str, CaseFields]) -> pd.DataFrame:
    """Per case and cross-section grid node the window-mean fields
    (:func:`ligwf.analysis.records.fields.fields_of`): node coordinates ``u``, ``v`` [m]
    in the plane normal to the drum axis (the axis at 0, ``v`` up), ``solid_fraction``
    [-], ``velocity_u``, ``velocity_v``, ``speed`` [m/s], granular ``temperature``
    [m^2/s^2] (nan where the node holds no material); ``frames``: the steady frames
    averaged. The arrays are (v, u): rows along v."""
    parts = []
    for case in cases.values():
        x = case.grid.coordinates()
        uu, vv = np.meshgrid(x, x)          # [row v, column u], as the arrays
        part = {"case_id": case.case_id, "cg": case.cg, "rule": case.rule,
                "replica": case.replica, "group": case.group, "frames": case.frames,
                "u": uu.ravel(), "v": vv.ravel()}
        part.update({name: values.ravel() for name, values in fields_of(case.mean()).items()})
        parts.append(pd.DataFrame(part))
    return typed(pd.concat(parts, ignore_index=True)) if parts else pd.DataFrame()


def plot_field(ax: Axes | None, case: CaseFields, quantity: str) -> Axes:
    """One window-mean field of one case on the cross-section (the report's
    :func:`ligwf.report.field_figures.field_map`; speed with the in-plane velocity as
    arrows), on the colour scale of its own finite range; velocities and temperature only
    where the solid fraction reaches the field error's ``MATERIAL_SOLID`` (as the report's
    maps: the dilute spray above the bed would set the scale otherwise)."""
    if quantity not in FIELD_UNITS:
        raise LigwfError(f"plot_field: quantity = {quantity!r} is not one of "
                         f"{', '.join(FIELD_UNITS)}")
    f = fields_of(case.mean())
    dilute = ~(f["solid_fraction"] >= MATERIAL_SOLID)
    f = {k: v if k == "solid_fraction" else np.where(dilute, np.nan, v) for k, v in f.items()}
    values = f[quantity]
    finite = values[np.isfinite(values)]
    top = float(np.abs(finite).max()) if finite.size else 1.0
    low = -top if CMAPS[quantity] == "RdBu_r" else 0.0
    arrows = (f["velocity_u"], f["velocity_v"]) if quantity == "speed" else None
    return field_map(axes(ax), case.grid, values, f"{case.case_id}: {quantity}", low,
                     top or 1.0, CMAPS[quantity], f"{quantity} [{FIELD_UNITS[quantity]}]",
                     arrows)
