"""Flow metrics of a drum run, from particle dumps: means AND fluctuations over time.

Everything is measured in the drum cross-section (coordinates u horizontal, v up; the axis
is averaged out). Per frame:

- free surface: the top of the bed in vertical strips across the central part of the drum
  (max of v + r per strip); the dynamic angle of repose is the magnitude of the slope of a
  straight-line fit through those points, in degrees.
- bed centre-of-mass angle: angle of the bed's centre of mass from straight down, degrees.
- velocity profile along the line through the drum centre normal to the free surface:
  particles within a band around that line, the velocity component along the surface,
  binned by distance along the line.
- flowing layer: from the top of the bed down to where that velocity changes sign
  (particles above flow down the slope, below they turn with the drum); its thickness
  and mean speed.
- rigid-block fraction: share of particles whose velocity is within ``rigid_tolerance``
  x (omega R) of the drum's rigid rotation omega x r. A frame with more than 90 % of the
  bed co-rotating is a *rigid frame* (the bed is carried up as one block: slumping).
- rms speed of the bed (its fluctuation over time is large when the bed slumps).

Over frames: mean and standard deviation of each scalar, the share of rigid frames, and a
velocity field on a grid of the cross-section averaged over frames.
Granule-derived quantities (largest granule fraction, share of frames in which one
granule holds > 99 % of the bed) come from the granule stage and are merged by the report.
"""

from __future__ import annotations

import warnings
from dataclasses import asdict, dataclass, field

import numpy as np

from ligwf.analysis.dumps import ParticleFrame
from ligwf.engine.mesh import axis_frame
from ligwf.scene.scaling import ScaledScene

RIGID_FRAME_SHARE = 0.9  # a frame is rigid when more than this share co-rotates


@dataclass(frozen=True)
class DrumGeometry:
    """What the flow metrics need to know about the drum (from the case's scaled scene)."""

    radius: float            # m
    axis: str                # x | y | z
    omega: float             # rad/s, rotation about +axis (counter-clockwise seen from +axis)
    d_mean: float            # m, a typical particle diameter (sets bins and bands)

    @classmethod
    def from_scaled(cls, scaled: ScaledScene) -> "DrumGeometry":
        d = np.asarray(scaled.diameters, float)
        f = np.asarray(scaled.number_fractions, float)
        return cls(radius=0.5 * scaled.drum_diameter, axis=scaled.axis,
                   omega=scaled.omega, d_mean=float(np.sum(d * f)))


@dataclass(frozen=True)
class FrameFlow:
    """Flow metrics of one frame."""

    step: int
    time: float
    angle_of_repose: float            # deg (nan when no surface could be fitted)
    com_angle: float                  # deg from straight down, + towards +u
    rigid_fraction: float             # share of particles co-rotating with the drum
    rms_speed: float                  # m/s
    flowing_layer_thickness: float    # m (nan when no sign change)
    flowing_layer_speed: float        # m/s
    profile_s: np.ndarray = field(repr=False)   # (B,) m, distance from centre along normal
    profile_v: np.ndarray = field(repr=False)   # (B,) m/s, mean velocity along the surface


def cross_section(frame: ParticleFrame, geo: DrumGeometry) -> tuple[np.ndarray, ...]:
    """(u, v, vel_u, vel_v) of every particle in the drum cross-section."""
    _, iu, iv = axis_frame(geo.axis)
    p, vel = frame.positions, frame.velocities
    return p[:, iu], p[:, iv], vel[:, iu], vel[:, iv]


def rigid_rotation_velocity(frame: ParticleFrame, geo: DrumGeometry) -> tuple[np.ndarray, np.ndarray]:
    """In-plane (u, v) velocity of rigid rotation omega x r about +axis.

    Computed in 3-D: for axis y the (u, v) = (x, z) plane is left-handed about +y, so a
    2-D formula would get the sense of rotation wrong.
    """
    ia, iu, iv = axis_frame(geo.axis)
    w = np.zeros(3)
    w[ia] = geo.omega
    rigid = np.cross(w, frame.positions)
    return rigid[:, iu], rigid[:, iv]


def free_surface(u: np.ndarray, v: np.ndarray, r: np.ndarray, geo: DrumGeometry,
                 span: float = 0.6) -> tuple[np.ndarray, np.ndarray]:
    """Top of the bed in strips of width ~2 d over |u| < span R: (u_centre, v_top) arrays."""
    width = 2.0 * geo.d_mean
    edges = np.arange(-span * geo.radius, span * geo.radius + width, width)
    strip = np.digitize(u, edges) - 1
    ok = (strip >= 0) & (strip < len(edges) - 1)
    tops = np.full(len(edges) - 1, -np.inf)
    counts = np.bincount(strip[ok], minlength=len(edges) - 1)
    np.maximum.at(tops, strip[ok], (v + r)[ok])
    keep = counts >= 2
    centres = 0.5 * (edges[:-1] + edges[1:])
    return centres[keep], tops[keep]


def surface_angle(us: np.ndarray, vs: np.ndarray) -> tuple[float, float]:
    """(angle in degrees, intercept in m) of a least-squares line v = a u + b."""
    if len(us) < 3:
        return float("nan"), float("nan")
    a, b = np.polyfit(us, vs, 1)
    return float(np.degrees(np.arctan(a))), float(b)


def frame_flow(frame: ParticleFrame, geo: DrumGeometry, rigid_tolerance: float = 0.2,
               band: float = 1.5, nbins: int = 24) -> FrameFlow:
    """All per-frame metrics (see the module docstring)."""
    u, v, vu, vv = cross_section(frame, geo)
    r = frame.radii
    mass = frame.volumes  # one density: volume weights are mass weights

    us, vs = free_surface(u, v, r, geo)
    angle, _ = surface_angle(us, vs)

    cu, cv = np.average(u, weights=mass), np.average(v, weights=mass)
    com_angle = float(np.degrees(np.arctan2(cu, -cv)))

    ru, rv = rigid_rotation_velocity(frame, geo)
    dev = np.hypot(vu - ru, vv - rv)
    rigid = float(np.mean(dev < rigid_tolerance * abs(geo.omega) * geo.radius))
    speed = np.sqrt(np.sum(frame.velocities**2, axis=1))
    rms = float(np.sqrt(np.mean(speed**2)))

    # profile along the line through the centre, normal to the surface (pointing up)
    if np.isfinite(angle):
        t = np.array([np.cos(np.radians(angle)), np.sin(np.radians(angle))])  # along surface
    else:
        t = np.array([1.0, 0.0])
    n = np.array([-t[1], t[0]])
    s = u * n[0] + v * n[1]                 # distance along the normal line
    off = u * t[0] + v * t[1]               # distance from the line
    near = np.abs(off) < band * geo.d_mean * 2
    vt = vu * t[0] + vv * t[1]              # velocity along the surface direction
    edges = np.linspace(-geo.radius, geo.radius, nbins + 1)
    idx = np.digitize(s[near], edges) - 1
    ok = (idx >= 0) & (idx < nbins)
    sums = np.bincount(idx[ok], weights=vt[near][ok], minlength=nbins)
    cnt = np.bincount(idx[ok], minlength=nbins)
    with np.errstate(invalid="ignore", divide="ignore"):
        prof = np.where(cnt > 0, sums / np.maximum(cnt, 1), np.nan)
    centres = 0.5 * (edges[:-1] + edges[1:])

    thickness, layer_speed = _flowing_layer(centres, prof, s[near], vt[near], geo)
    return FrameFlow(step=frame.step, time=frame.time, angle_of_repose=abs(angle),
                     com_angle=com_angle, rigid_fraction=rigid, rms_speed=rms,
                     flowing_layer_thickness=thickness, flowing_layer_speed=layer_speed,
                     profile_s=centres, profile_v=prof)


def _flowing_layer(centres, prof, s, vt, geo: DrumGeometry) -> tuple[float, float]:
    """Thickness and mean speed of the layer above the velocity reversal on the profile."""
    filled = np.flatnonzero(np.isfinite(prof))
    if len(filled) < 2 or len(s) == 0:
        return float("nan"), float("nan")
    top = float(np.max(s)) + 0.5 * geo.d_mean
    # walk down from the top bin: flowing while the velocity has the sign of the top bin
    sign = np.sign(prof[filled[-1]])
    zero = None
    for k in filled[::-1]:
        if np.sign(prof[k]) != sign:
            zero = centres[k]
            break
    if zero is None or sign == 0:
        return float("nan"), float("nan")
    layer = s > zero
    return top - float(zero), float(np.mean(np.abs(vt[layer]))) if layer.any() else float("nan")


@dataclass(frozen=True)
class FlowSummary:
    """Time statistics over the steady frames of one run."""

    frames: int
    angle_of_repose_mean: float
    angle_of_repose_std: float
    com_angle_mean: float
    com_angle_std: float
    rigid_frame_share: float          # share of frames with > 90 % co-rotating
    rigid_fraction_mean: float
    rms_speed_mean: float
    rms_speed_rel_fluctuation: float  # std / mean over frames
    flowing_layer_thickness_mean: float
    flowing_layer_speed_mean: float
    profile_s: list[float]
    profile_v_mean: list[float]
    profile_v_std: list[float]

    def scalars(self) -> dict:
        return {k: v for k, v in asdict(self).items() if not isinstance(v, list)}


def _nanstat(x: np.ndarray, fn) -> float:
    x = x[np.isfinite(x)]
    return float(fn(x)) if len(x) else float("nan")


def summarise(flows: list[FrameFlow]) -> FlowSummary:
    """Mean and fluctuation over frames (pass only the steady part of the run)."""
    if not flows:
        raise ValueError("no frames to summarise")
    ang = np.array([f.angle_of_repose for f in flows])
    com = np.array([f.com_angle for f in flows])
    rig = np.array([f.rigid_fraction for f in flows])
    rms = np.array([f.rms_speed for f in flows])
    thick = np.array([f.flowing_layer_thickness for f in flows])
    lspeed = np.array([f.flowing_layer_speed for f in flows])
    prof = np.vstack([f.profile_v for f in flows])
    with np.errstate(invalid="ignore"), warnings.catch_warnings():
        warnings.simplefilter("ignore", RuntimeWarning)  # all-nan bins stay nan
        pmean = np.nanmean(prof, axis=0)
        pstd = np.nanstd(prof, axis=0)
    rms_mean = float(np.mean(rms))
    return FlowSummary(
        frames=len(flows),
        angle_of_repose_mean=_nanstat(ang, np.mean), angle_of_repose_std=_nanstat(ang, np.std),
        com_angle_mean=float(np.mean(com)), com_angle_std=float(np.std(com)),
        rigid_frame_share=float(np.mean(rig > RIGID_FRAME_SHARE)),
        rigid_fraction_mean=float(np.mean(rig)),
        rms_speed_mean=rms_mean,
        rms_speed_rel_fluctuation=float(np.std(rms) / rms_mean) if rms_mean > 0 else float("nan"),
        flowing_layer_thickness_mean=_nanstat(thick, np.mean),
        flowing_layer_speed_mean=_nanstat(lspeed, np.mean),
        profile_s=[float(x) for x in flows[0].profile_s],
        profile_v_mean=[float(x) for x in pmean], profile_v_std=[float(x) for x in pstd],
    )


def velocity_field(frames: list[ParticleFrame], geo: DrumGeometry, cells: int = 24
                   ) -> tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray]:
    """Mean in-plane velocity on a cells x cells grid over the cross-section.

    Returns (u centres, v centres, mean vel_u, mean vel_v) with nan in empty cells.
    """
    edges = np.linspace(-geo.radius, geo.radius, cells + 1)
    su = np.zeros((cells, cells))
    sv = np.zeros((cells, cells))
    cnt = np.zeros((cells, cells))
    for fr in frames:
        u, v, vu, vv = cross_section(fr, geo)
        iu = np.clip(np.digitize(u, edges) - 1, 0, cells - 1)
        iv = np.clip(np.digitize(v, edges) - 1, 0, cells - 1)
        np.add.at(su, (iv, iu), vu)
        np.add.at(sv, (iv, iu), vv)
        np.add.at(cnt, (iv, iu), 1)
    with np.errstate(invalid="ignore", divide="ignore"):
        mu = np.where(cnt > 0, su / cnt, np.nan)
        mv = np.where(cnt > 0, sv / cnt, np.nan)
    c = 0.5 * (edges[:-1] + edges[1:])
    return c, c, mu, mv


def profile_l2_error(s_ref: list[float], v_ref: list[float], s: list[float], v: list[float]) -> float:
    """Relative L2 difference of a velocity profile against a reference, on common bins.

    ||v - v_ref|| / ||v_ref|| over the bins both profiles fill (profiles are compared in
    drum coordinates, which CG does not change).
    """
    s_ref, v_ref, s, v = map(lambda a: np.asarray(a, float), (s_ref, v_ref, s, v))
    vi = np.interp(s_ref, s, np.where(np.isfinite(v), v, np.nan)) if len(s) else np.full_like(s_ref, np.nan)
    ok = np.isfinite(v_ref) & np.isfinite(vi)
    if not ok.any():
        return float("nan")
    norm = np.linalg.norm(v_ref[ok])
    return float(np.linalg.norm(vi[ok] - v_ref[ok]) / norm) if norm > 0 else float("nan")
