"""Flow metrics on synthetic beds with known answers (and on a real dump in the study test)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ligwf.analysis.frames.dumps import ParticleFrame
from ligwf.analysis.flow.frame import DrumGeometry, frame_flow, profile_l2_error, rising_side, summarise

R, D = 0.025, 0.001


def bed(angle_deg: float, axis: str = "y", omega: float = 3.0, rigid: bool = True,
        seed: int = 0, offset: float = 0.0, airborne: int = 0, clump: bool = False
        ) -> tuple[ParticleFrame, DrumGeometry]:
    """Particles filling the drum below a plane surface tilted by ``angle_deg`` (signed: a
    positive angle rises towards the wall that moves up), ``offset`` m above the centre;
    optionally ``airborne`` particles flying above the surface and a clump carried up by
    a lifter at the rising wall (the outliers a robust fit must ignore)."""
    rng = np.random.default_rng(seed)
    side = rising_side(DrumGeometry(radius=R, axis=axis, omega=omega, d_mean=D))
    pts = rng.uniform(-R, R, size=(20000, 2))
    t = math.radians(angle_deg) * side
    height = -np.sin(t) * pts[:, 0] + np.cos(t) * pts[:, 1]     # along the surface normal
    inside = (np.hypot(pts[:, 0], pts[:, 1]) < R - D) & (height < offset)
    uv = pts[inside]
    extra = []
    if airborne:
        along = rng.uniform(-0.5 * R, 0.5 * R, airborne)
        up = offset + rng.uniform(2 * D, 5 * D, airborne)
        extra.append(np.c_[along * np.cos(t) - up * np.sin(t), along * np.sin(t) + up * np.cos(t)])
    if clump:
        a = rng.uniform(0, 2 * np.pi, 60)
        centre = np.array([side * 0.8 * R, 0.45 * R])
        extra.append(centre + 2 * D * np.c_[np.cos(a), np.sin(a)] * rng.uniform(0, 1, (60, 1)))
    if extra:
        uv = np.vstack([uv, *extra])
    n = len(uv)
    ia, iu, iv = {"x": (0, 1, 2), "y": (1, 0, 2), "z": (2, 0, 1)}[axis]
    pos = np.zeros((n, 3))
    pos[:, iu], pos[:, iv] = uv[:, 0], uv[:, 1]
    pos[:, ia] = rng.uniform(0, 0.01, n)
    w = np.zeros(3)
    w[ia] = omega
    vel = np.cross(w, pos) if rigid else rng.normal(0, 0.1, (n, 3))
    frame = ParticleFrame(Path("synthetic"), 0, 0.0, np.arange(1, n + 1), np.ones(n, np.int32),
                          pos, vel, np.full(n, 0.5 * D), None)
    return frame, DrumGeometry(radius=R, axis=axis, omega=omega, d_mean=D)


@pytest.mark.parametrize("axis", ["x", "y", "z"])
@pytest.mark.parametrize("omega", [3.0, -3.0])
@pytest.mark.parametrize("angle", [0.0, 20.0, 35.0, -15.0])
def test_angle_of_repose_of_a_plane_surface(axis, omega, angle):
    """Known surface angle, both senses of rotation: recovered within 0.5 deg, signed."""
    frame, geo = bed(angle, axis, omega)
    f = frame_flow(frame, geo)
    assert f.angle_of_repose == pytest.approx(angle, abs=0.5)


@pytest.mark.parametrize("omega", [3.0, -3.0])
@pytest.mark.parametrize("offset", [-0.4 * R, 0.0, 0.3 * R])
def test_angle_ignores_airborne_particles_and_lifter_clumps(omega, offset):
    frame, geo = bed(36.0, "y", omega, offset=offset, airborne=15, clump=True, seed=3)
    assert frame_flow(frame, geo).angle_of_repose == pytest.approx(36.0, abs=0.5)


def test_velocity_profile_is_on_the_normalised_depth():
    """Rigid rotation: the downhill velocity is negative everywhere below the surface
    and grows with depth (farther from the centre line... towards the wall)."""
    frame, geo = bed(30.0, omega=3.0, offset=-0.3 * R)
    f = frame_flow(frame, geo)
    assert f.profile_s[0] > 0 and f.profile_s[-1] < 1
    v = f.profile_v[np.isfinite(f.profile_v)]
    assert len(v) >= 12
    # rigid rotation about the centre: along the downhill tangent the speed is omega x
    # distance from the centre along the normal, which is (offset - xi * depth)
    depth = geo.radius - 0.3 * R
    expect = -3.0 * (0.3 * R + f.profile_s * depth)
    ok = np.isfinite(f.profile_v)
    assert np.allclose(f.profile_v[ok], expect[ok], atol=0.1 * 3.0 * D + 0.002)


@pytest.mark.parametrize("axis", ["x", "y", "z"])
def test_rigid_rotation_is_detected_for_every_axis(axis):
    frame, geo = bed(30.0, axis, rigid=True)
    assert frame_flow(frame, geo).rigid_fraction == 1.0
    frame, geo = bed(30.0, axis, rigid=False)
    assert frame_flow(frame, geo).rigid_fraction < 0.3


def test_centre_of_mass_angle_follows_the_tilt():
    flat, geo = bed(0.0)
    tilted, _ = bed(30.0)
    assert frame_flow(flat, geo).com_angle == pytest.approx(0.0, abs=1.0)
    assert abs(frame_flow(tilted, geo).com_angle) > 5.0


def test_summary_counts_rigid_frames_and_fluctuation():
    frames = [frame_flow(*bed(30.0, rigid=(k % 2 == 0), seed=k)) for k in range(6)]
    s = summarise(frames)
    assert s.frames == 6
    assert s.rigid_frame_share == pytest.approx(0.5)
    assert s.angle_of_repose_std < 2.0


def test_profile_error_is_zero_against_itself_and_scales():
    s = [0.0, 1.0, 2.0, 3.0]
    v = [1.0, 0.5, -0.5, -1.0]
    assert profile_l2_error(s, v, s, v) == 0.0
    assert profile_l2_error(s, v, s, [2 * x for x in v]) == pytest.approx(1.0)
