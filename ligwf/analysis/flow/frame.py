"""Flow metrics of a drum run, from particle dumps: means AND fluctuations over time.

Everything is measured in the drum cross-section (coordinates u horizontal, v up; the axis
is averaged out). Per frame:

- free surface and dynamic angle of repose: a robust straight-line fit of the surface
  (:mod:`ligwf.analysis.flow.surface`: centre-of-mass first guess, strip tops across the
  central chord with airborne particles skipped, MAD outlier rejection), the angle signed
  with respect to the rotation (positive: rising towards the wall that moves up), degrees.
- bed centre-of-mass angle: angle of the bed's centre of mass from straight down, degrees.
- velocity profile along the normal to the free surface through the drum centre, on a
  normalised depth xi = (distance below the free surface) / (bed depth on that line), 0 at
  the surface, 1 at the drum wall: particles within a band of half-width
  ``PROFILE_HALF_WIDTH`` x drum radius around the line (the same physical width at every
  CG level), their velocity along the downhill surface direction (positive in the flowing
  layer, negative where the bed turns with the drum), averaged in ``PROFILE_BINS`` bins.
- flowing layer: the grains above the first depth where that velocity changes sign (the
  zero crossing interpolated between the bins' mean particle depths, not their centres: a
  bin holding one or two rows of coarse grains has its mean depth off its centre); its
  thickness (m) is mass-equivalent: the layer's grain volume in the band over the band's
  width times the packing of the bed below the crossing (its grain volume over the band's
  area from the crossing to the drum wall, the wall one grain radius in for centres), so
  the fitted surface, whose height above the grains grows with their size, does not enter;
  and their mean speed.
- rigid-block fraction: share of particles whose velocity is within ``rigid_tolerance``
  x (omega R) of the drum's rigid rotation omega x r. A frame with more than 90 % of the
  bed co-rotating is a *rigid frame* (the bed is carried up as one block: slumping).
- rms speed of the bed (its fluctuation over time is large when the bed slumps) and the
  kinetic energy per unit mass (the spin-up signal of :mod:`ligwf.analysis.flow.steady`).

Over frames: mean and standard deviation of each scalar, the share of rigid frames, and a
velocity field on a grid of the cross-section averaged over frames.
Granule-derived quantities (largest granule fraction, share of frames in which one
granule holds > 99 % of the bed) come from the granule stage and are merged by the report.
The report's flow metrics are registered in :mod:`ligwf.analysis.flow.registry`.
"""

from __future__ import annotations

import math
import warnings
from dataclasses import asdict, dataclass, field

import numpy as np

from ligwf.analysis.frames.dumps import ParticleFrame
from ligwf.analysis.records.statistics import relative_l2
from ligwf.analysis.flow.surface import fit_surface
from ligwf.scene.axis import Axis
from ligwf.scene.grains import scaled_mean_diameter
from ligwf.scene.scaled import ScaledScene

RIGID_FRAME_SHARE = 0.9  # a frame is rigid when more than this share co-rotates
PROFILE_HALF_WIDTH = 0.15  # profile band half-width / drum radius (CG-independent)
PROFILE_BINS = 16         # bins of the normalised depth xi in [0, 1]


@dataclass(frozen=True)
class DrumGeometry:
    """What the flow metrics need to know about the drum (from the case's scaled scene)."""

    radius: float            # m
    axis: Axis               # the drum axis (a letter is taken as its Axis)
    omega: float             # rad/s, rotation about +axis (counter-clockwise seen from +axis)
    d_mean: float            # m, a typical particle diameter (sets bins and bands)
    #: m, the angle's surface strips (the study's one resolution, surface.study_strip);
    #: None: twice this case's own d_mean
    strip: float | None = None

    def __post_init__(self) -> None:
        object.__setattr__(self, "axis", Axis(self.axis))

    @classmethod
    def from_scaled(cls, scaled: ScaledScene, strip: float | None = None) -> "DrumGeometry":
        return cls(radius=0.5 * scaled.drum.diameter, axis=scaled.drum.axis,
                   omega=scaled.drum.omega, d_mean=scaled_mean_diameter(scaled), strip=strip)


@dataclass(frozen=True)
class FrameFlow:
    """Flow metrics of one frame."""

    step: int
    time: float
    angle_of_repose: float            # deg, signed (nan when no surface could be fitted)
    com_angle: float                  # deg from straight down, + towards +u
    rigid_fraction: float             # share of particles co-rotating with the drum
    rms_speed: float                  # m/s
    kinetic_energy: float             # J/kg, translational, per unit mass (mean v^2 / 2)
    flowing_layer_thickness: float    # m (nan when no sign change)
    flowing_layer_speed: float        # m/s
    profile_s: np.ndarray = field(repr=False)   # (B,) normalised depth xi of the bin centres
    profile_v: np.ndarray = field(repr=False)   # (B,) m/s, mean downhill velocity (nan: empty)


def cross_section(frame: ParticleFrame, geo: DrumGeometry) -> tuple[np.ndarray, ...]:
    """(u, v, vel_u, vel_v) of every particle in the drum cross-section."""
    _, iu, iv = geo.axis.frame
    p, vel = frame.positions, frame.velocities
    return p[:, iu], p[:, iv], vel[:, iu], vel[:, iv]


def rigid_rotation_velocity(frame: ParticleFrame, geo: DrumGeometry) -> tuple[np.ndarray, np.ndarray]:
    """In-plane (u, v) velocity of rigid rotation omega x r about +axis.

    Computed in 3-D: for axis y the (u, v) = (x, z) plane is left-handed about +y, so a
    2-D formula would get the sense of rotation wrong.
    """
    ia, iu, iv = geo.axis.frame
    w = np.zeros(3)
    w[ia] = geo.omega
    rigid = np.cross(w, frame.positions)
    return rigid[:, iu], rigid[:, iv]


def rising_side(geo: DrumGeometry) -> float:
    """+1 when the drum wall at +u moves up (rigid rotation at (u, v) = (R, 0)), else -1."""
    ia, iu, iv = geo.axis.frame
    w, p = np.zeros(3), np.zeros(3)
    w[ia], p[iu] = geo.omega, geo.radius
    return 1.0 if np.cross(w, p)[iv] >= 0 else -1.0


def frame_flow(frame: ParticleFrame, geo: DrumGeometry, rigid_tolerance: float = 0.2) -> FrameFlow:
    """All per-frame metrics (see the module docstring)."""
    u, v, vu, vv = cross_section(frame, geo)
    r = frame.radii
    mass = frame.volumes  # one density: volume weights are mass weights
    side = rising_side(geo)
    surf = fit_surface(u, v, r, geo.radius, geo.d_mean, side, strip=geo.strip)

    cu, cv = np.average(u, weights=mass), np.average(v, weights=mass)
    com_angle = float(np.degrees(np.arctan2(cu, -cv)))

    ru, rv = rigid_rotation_velocity(frame, geo)
    dev = np.hypot(vu - ru, vv - rv)
    rigid = float(np.mean(dev < rigid_tolerance * abs(geo.omega) * geo.radius))
    speed2 = np.sum(frame.velocities**2, axis=1)
    rms = float(np.sqrt(np.mean(speed2)))
    kinetic = float(0.5 * np.average(speed2, weights=mass))

    centres = (np.arange(PROFILE_BINS) + 0.5) / PROFILE_BINS
    prof = np.full(PROFILE_BINS, np.nan)
    thickness = layer_speed = float("nan")
    if surf is not None:
        t = np.radians(surf.tangent_deg)
        x = u * np.cos(t) + v * np.sin(t)            # along the surface
        y = -u * np.sin(t) + v * np.cos(t)           # along its upward normal
        depth = surf.offset + geo.radius             # bed depth on the line through the centre
        near = np.abs(x) < PROFILE_HALF_WIDTH * geo.radius
        xi = np.clip((surf.offset - y[near]) / depth, 0.0, 1.0 - 1e-12)
        down = -side * (vu[near] * np.cos(t) + vv[near] * np.sin(t))
        idx = (xi * PROFILE_BINS).astype(int)
        sums = np.bincount(idx, weights=down, minlength=PROFILE_BINS)
        cnt = np.bincount(idx, minlength=PROFILE_BINS)
        prof = np.where(cnt > 0, sums / np.maximum(cnt, 1), np.nan)
        mean_xi = np.where(cnt > 0, np.bincount(idx, weights=xi, minlength=PROFILE_BINS)
                           / np.maximum(cnt, 1), np.nan)
        band = _Band(PROFILE_HALF_WIDTH * geo.radius, geo.radius - float(np.mean(r)),
                     surf.offset, depth)
        thickness, layer_speed = _flowing_layer(mean_xi, prof, xi, down,
                                                frame.volumes[near], band)
    return FrameFlow(step=frame.step, time=frame.time,
                     angle_of_repose=surf.angle_deg if surf else float("nan"),
                     com_angle=com_angle, rigid_fraction=rigid, rms_speed=rms,
                     kinetic_energy=kinetic,
                     flowing_layer_thickness=thickness, flowing_layer_speed=layer_speed,
                     profile_s=centres, profile_v=prof)


@dataclass(frozen=True)
class _Band:
    """The profile's band in the surface's frame: half-width (m), the radius the grains'
    centres reach (m), the surface's offset from the drum axis and the bed depth on the
    centre line (m)."""

    half_width: float
    centre_radius: float
    offset: float
    depth: float

    def area_below(self, level: float) -> float:
        """Area (m^2) of the band between the height ``level`` (from the axis, along the
        surface normal) and the circle the grains' centres reach."""
        w, rc = self.half_width, self.centre_radius
        if w >= rc:
            return float("nan")
        chord = w * math.sqrt(rc * rc - w * w) + rc * rc * math.asin(w / rc)
        return 2.0 * w * level + chord


def _flowing_layer(mean_xi, prof, xi, down, volumes, band: _Band) -> tuple[float, float]:
    """Mass-equivalent thickness (m) and mean speed (m/s) of the layer above the first
    reversal of the downhill velocity below the surface (module docstring); nan when the
    profile does not reverse or no grain lies below the reversal."""
    filled = np.flatnonzero(np.isfinite(prof) & np.isfinite(mean_xi))
    if len(filled) < 2 or prof[filled[0]] <= 0:
        return float("nan"), float("nan")
    below = filled[prof[filled] <= 0]
    if not len(below):
        return float("nan"), float("nan")
    k = below[0]
    above = filled[filled < k][-1]
    # linear zero crossing between the last flowing bin and the first reversed one, each at
    # the mean depth of its particles
    zero = mean_xi[above] + ((mean_xi[k] - mean_xi[above]) * prof[above]
                             / (prof[above] - prof[k]))
    layer = xi < zero
    speed = float(np.mean(np.abs(down[layer]))) if layer.any() else float("nan")
    packed = float(np.sum(volumes[~layer])) / band.area_below(band.offset - zero * band.depth)
    if not packed > 0:
        return float("nan"), speed
    return float(np.sum(volumes[layer])) / (packed * 2.0 * band.half_width), speed


@dataclass(frozen=True)
class FlowSummary:
    """Time statistics over the steady frames of one run.

    ``angle_of_repose`` is the mean of the frames' angles (those with a fitted surface):
    the value of the registered flow metric of that name, so the flow table has it once.
    """

    frames: int
    angle_of_repose: float            # deg, mean over the frames
    angle_of_repose_std: float
    com_angle_mean: float
    com_angle_std: float
    rigid_frame_share: float          # share of frames with > 90 % co-rotating
    rigid_fraction_mean: float
    rms_speed_mean: float
    rms_speed_rel_fluctuation: float  # std / mean over frames
    kinetic_energy_mean: float        # J/kg
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
        angle_of_repose=_nanstat(ang, np.mean), angle_of_repose_std=_nanstat(ang, np.std),
        com_angle_mean=float(np.mean(com)), com_angle_std=float(np.std(com)),
        rigid_frame_share=float(np.mean(rig > RIGID_FRAME_SHARE)),
        rigid_fraction_mean=float(np.mean(rig)),
        rms_speed_mean=rms_mean,
        rms_speed_rel_fluctuation=float(np.std(rms) / rms_mean) if rms_mean > 0 else float("nan"),
        kinetic_energy_mean=float(np.mean([f.kinetic_energy for f in flows])),
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
    """Relative L2 difference of a velocity profile against a reference.

    Both profiles are on the normalised depth xi (surface 0, wall 1), so bins compare one
    to one across CG levels; a profile on other bin centres is interpolated onto the
    reference's (nan where it has no data).
    """
    s_ref, v_ref, s, v = map(lambda a: np.asarray(a, float), (s_ref, v_ref, s, v))
    if len(s) != len(s_ref) or not np.allclose(s, s_ref):
        ok = np.isfinite(v)
        v = (np.interp(s_ref, s[ok], v[ok], left=np.nan, right=np.nan) if ok.sum() > 1
             else np.full_like(s_ref, np.nan))
    return float(relative_l2(v_ref, v))
