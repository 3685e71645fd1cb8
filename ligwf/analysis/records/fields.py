"""The field record: per case the coarse-grained cross-section fields of its steady window.

Written by ``ligwf analyse`` (the flow stage, :mod:`ligwf.analysis.flow.fields` computes
them) into the analysis folder as one compressed numpy archive (``layout.FIELDS_DATA``,
listed with its digest in the analysis record) and, per case, a VTK ImageData file of the
time-averaged fields that ParaView opens (``layout.field_image``). The inference layer
reads the archive the analysis record lists through :func:`recorded_fields` and computes
only statistics of it (the field error, its interval and its CG1 floor:
:mod:`ligwf.inference.field_errors`).

Per case and steady frame, the kernel sums ``MOMENTS`` on the grid nodes (units: phi
dimensionless, the fluxes m/s, the fluctuation m^2/s^2, all per unit solid fraction
times phi); any frame weighting (the window mean, a bootstrap resample) of these sums
gives the fields of that weighting through :func:`fields_of`.

Per case also, at each kernel width of ``CRITERION_KERNELS`` (CG1 mean diameters), the
window-mean in-plane kernel sums of the whole window and of its two halves
(:class:`WindowMeans`), with the drum's angular velocity and radius: what the field
criterion reads (the drum-frame velocity in the flowing layer, per run,
:mod:`ligwf.inference.field_errors`).
"""

from __future__ import annotations

import base64
import io
import json
import math
import struct
import zipfile
from dataclasses import dataclass, field
from pathlib import Path

import numpy as np

from ligwf.analysis.records.analysis_record import AnalysisRecord
from ligwf.analysis.records.provenance import StaleAnalysis
from ligwf.scene.axis import Axis
from ligwf.study import layout

#: per-frame kernel sums on the grid, in this order (axis 1 of ``CaseFields.moments``)
MOMENTS = ("solid_fraction", "flux_u", "flux_v", "flux_axial", "fluctuation")
#: the kernel widths (CG1 mean diameters) at which every case's window means are kept for
#: the field criterion (it is reported at each; the verdict uses ``analysis.field_kernel``)
CRITERION_KERNELS = (1.0, 2.0, 4.0)
#: the in-plane kernel sums of :class:`WindowMeans`: the first ``IN_PLANE`` of ``MOMENTS``
IN_PLANE = 3
#: the parts of the window of :class:`WindowMeans`, in this order
WINDOW_PARTS = ("window", "first_half", "second_half")
#: below this solid fraction a node holds no material: no velocity or temperature there
EMPTY_SOLID = 1e-3
#: the derived fields, their units (the ImageData arrays and the report's maps)
FIELD_UNITS = {"solid_fraction": "-", "velocity_u": "m/s", "velocity_v": "m/s",
               "speed": "m/s", "temperature": "m^2/s^2"}


@dataclass(frozen=True)
class FieldGrid:
    """Square node grid of the cross-section (nodes x nodes, same spacing on both axes),
    with the kernel that smoothed it."""

    origin: float      # m, u and v of node 0 (the drum axis is at 0)
    spacing: float     # m, node spacing h
    nodes: int         # nodes per axis
    width: float       # m, kernel standard deviation (a physical length, CG-independent)
    length: float      # m, periodic length the fields are averaged over
    axis: Axis         # the drum axis (u, v: Axis.frame); read back from its letter

    def __post_init__(self) -> None:
        object.__setattr__(self, "axis", Axis(self.axis))

    def coordinates(self) -> np.ndarray:
        """(nodes,) node coordinates, m (the same for u and v)."""
        return self.origin + self.spacing * np.arange(self.nodes)

    def to_json(self) -> dict:
        return {**self.__dict__, "axis": self.axis.value}


@dataclass(frozen=True)
class WindowMeans:
    """A case's window-mean in-plane kernel sums at one kernel width: the whole steady
    window and its first and second half (the halves give a CG1-vs-CG1 comparison even
    from few seeds)."""

    kernel: float      # CG1 mean diameters
    grid: FieldGrid
    sums: np.ndarray = field(repr=False, compare=False)   # (len(WINDOW_PARTS), IN_PLANE, n, n)

    def part(self, name: str) -> np.ndarray:
        """(IN_PLANE, n, n) kernel sums of one part of the window (``WINDOW_PARTS``)."""
        return self.sums[WINDOW_PARTS.index(name)]


@dataclass(frozen=True)
class CaseFields:
    """The kernel sums of one case's steady frames (see the module docstring)."""

    case_id: str
    cg: float
    rule: str
    replica: int
    group: str
    grid: FieldGrid
    steps: np.ndarray = field(repr=False, compare=False)     # (F,) steps of the frames
    moments: np.ndarray = field(repr=False, compare=False)   # (F, len(MOMENTS), n, n)
    omega: float = math.nan     # rad/s, the drum's rotation about +axis (nan: not recorded)
    radius: float = math.nan    # m, the drum radius
    window_means: tuple[WindowMeans, ...] = field(default=(), repr=False, compare=False)

    def at_kernel(self, kernel: float) -> WindowMeans | None:
        """The window means at ``kernel`` CG1 diameters (None: not recorded)."""
        return next((w for w in self.window_means if math.isclose(w.kernel, kernel)), None)

    @property
    def frames(self) -> int:
        return len(self.steps)

    def mean(self) -> np.ndarray:
        """The window-mean kernel sums (len(MOMENTS), n, n)."""
        return self.moments.mean(axis=0)

    def speed_signal(self) -> np.ndarray:
        """(F,) per-frame solid-weighted mean in-plane speed, m/s: the frame series whose
        autocorrelation sets the bootstrap block length."""
        m = self.moments
        flux = np.hypot(m[:, 1], m[:, 2]).sum(axis=(1, 2))
        solid = m[:, 0].sum(axis=(1, 2))
        return np.where(solid > 0, flux / np.where(solid > 0, solid, 1.0), 0.0)


def fields_of(sums: np.ndarray) -> dict[str, np.ndarray]:
    """The fields of kernel sums ``(..., len(MOMENTS), n, n)`` (a frame, the window mean,
    bootstrap draws): solid fraction, in-plane velocity and speed (m/s), granular
    temperature T = <|c'|^2> / 3 (m^2/s^2); nan where phi < ``EMPTY_SOLID``."""
    phi = sums[..., 0, :, :]
    ok = phi >= EMPTY_SOLID
    safe = np.where(ok, phi, 1.0)
    u = np.where(ok, sums[..., 1, :, :] / safe, np.nan)
    v = np.where(ok, sums[..., 2, :, :] / safe, np.nan)
    t = np.where(ok, np.maximum(sums[..., 4, :, :], 0.0) / (3.0 * safe), np.nan)
    return {"solid_fraction": phi, "velocity_u": u, "velocity_v": v,
            "speed": np.hypot(u, v), "temperature": t}


def fields_bytes(cases: list[CaseFields]) -> bytes:
    """The archive of a study's fields (float32 sums: 7 significant digits, half the
    size): ``index`` (JSON: per case its identity and grid) and ``<case>/steps``,
    ``<case>/moments`` arrays."""
    arrays = {"index": np.frombuffer(json.dumps(
        [{"case_id": c.case_id, "cg": c.cg, "rule": c.rule, "replica": c.replica,
          "group": c.group, "grid": c.grid.to_json(), "omega": c.omega, "radius": c.radius,
          "window_means": [{"kernel": w.kernel, "grid": w.grid.to_json()}
                           for w in c.window_means]}
         for c in cases]).encode(), np.uint8)}
    for k, c in enumerate(cases):
        arrays[f"{k}/steps"] = np.asarray(c.steps, np.int64)
        arrays[f"{k}/moments"] = np.asarray(c.moments, np.float32)
        for j, w in enumerate(c.window_means):
            arrays[f"{k}/window_means/{j}"] = np.asarray(w.sums, np.float32)
    buf = io.BytesIO()
    # np.savez stamps each member with the current time: a fixed stamp keeps the bytes
    # (and the digest in the analysis record) the same for the same fields, whatever the
    # run or the number of ranks
    with zipfile.ZipFile(buf, "w", zipfile.ZIP_DEFLATED) as z:
        for name, array in arrays.items():
            member = io.BytesIO()
            np.lib.format.write_array(member, np.ascontiguousarray(array), allow_pickle=False)
            info = zipfile.ZipInfo(f"{name}.npy", date_time=(1980, 1, 1, 0, 0, 0))
            info.compress_type = zipfile.ZIP_DEFLATED
            z.writestr(info, member.getvalue())
    return buf.getvalue()


def read_fields(path: Path) -> dict[str, CaseFields]:
    """The fields of every case in the archive at ``path`` (case_id -> CaseFields; an
    archive from before the window means reads without them: omega and radius nan);
    OSError / ValueError / KeyError when it is missing or not one."""
    with np.load(Path(path), allow_pickle=False) as z:
        index = json.loads(bytes(z["index"]).decode())
        out = {}
        for k, d in enumerate(index):
            means = tuple(WindowMeans(kernel=float(w["kernel"]), grid=FieldGrid(**w["grid"]),
                                      sums=z[f"{k}/window_means/{j}"].astype(np.float64))
                          for j, w in enumerate(d.get("window_means", [])))
            out[d["case_id"]] = CaseFields(
                case_id=d["case_id"], cg=float(d["cg"]), rule=d["rule"],
                replica=int(d["replica"]), group=d["group"], grid=FieldGrid(**d["grid"]),
                steps=z[f"{k}/steps"], moments=z[f"{k}/moments"].astype(np.float64),
                omega=float(d.get("omega", math.nan)), radius=float(d.get("radius", math.nan)),
                window_means=means)
    return out


def recorded_fields(analysis_dir: Path) -> dict[str, CaseFields]:
    """The fields of every case the analysis in ``analysis_dir`` recorded ({} when its
    record lists no field archive: an analysis from before the fields, or without a
    measured case; a stale archive an older analysis left is never read). StaleAnalysis
    (one line) when the listed archive cannot be read."""
    path = Path(analysis_dir) / layout.FIELDS_DATA
    record = AnalysisRecord.read(analysis_dir)
    if record is None or not record.wrote(layout.FIELDS_DATA) or not path.is_file():
        return {}
    try:
        return read_fields(path)
    except (OSError, ValueError, KeyError, zipfile.BadZipFile) as exc:
        raise StaleAnalysis(f"{path}: not a field archive ligwf wrote ({exc}); run `ligwf "
                            "analyse` again") from None


def _binary(a: np.ndarray) -> str:
    """A VTK XML inline binary data array: base64 of the byte count (UInt32) and the
    little-endian float64 values (nan kept: VTK's ASCII reader cannot parse it)."""
    raw = np.ascontiguousarray(np.ravel(a), dtype="<f8").tobytes()
    return base64.b64encode(struct.pack("<I", len(raw)) + raw).decode()


def image_text(case: CaseFields) -> str:
    """VTK XML ImageData (``.vti``, inline base64) of a case's window-mean fields, opened by
    ParaView: one slab of nodes x nodes points in the plane at axial coordinate 0, in the
    drum's own coordinates (the in-plane velocity as a 3-vector with zero axial part)."""
    g = case.grid
    f = fields_of(case.mean())
    ia, iu, iv = g.axis.frame
    origin, spacing, extent = [0.0] * 3, [g.spacing] * 3, [0] * 6
    origin[iu] = origin[iv] = g.origin
    extent[2 * iu + 1] = extent[2 * iv + 1] = g.nodes - 1
    vel = np.zeros((g.nodes, g.nodes, 3))
    vel[..., iu], vel[..., iv] = f["velocity_u"], f["velocity_v"]
    # VTK orders points x fastest: arrays are (v, u) = rows v; reorder when u is not x
    def order(a):
        return a if iu < iv else np.swapaxes(a, 0, 1)
    arrays = [f'<DataArray type="Float64" Name="{name}" format="binary">'
              f"{_binary(order(f[name]))}</DataArray>"
              for name in ("solid_fraction", "speed", "temperature")]
    arrays.append('<DataArray type="Float64" Name="velocity" NumberOfComponents="3" '
                  f'format="binary">{_binary(order(vel))}</DataArray>')
    ext = " ".join(map(str, extent))
    return ('<?xml version="1.0"?>\n<VTKFile type="ImageData" version="0.1" '
            'byte_order="LittleEndian">\n'
            f'<ImageData WholeExtent="{ext}" Origin="{" ".join(map(str, origin))}" '
            f'Spacing="{" ".join(map(str, spacing))}">\n<Piece Extent="{ext}">\n'
            '<PointData Scalars="solid_fraction" Vectors="velocity">\n'
            + "\n".join(arrays) + "\n</PointData>\n</Piece>\n</ImageData>\n</VTKFile>\n")
