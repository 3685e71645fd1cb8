"""Flow metrics on synthetic beds with known answers (and on a real dump in the study test)."""

from __future__ import annotations

import math
from pathlib import Path

import numpy as np
import pytest

from ligwf.analysis.dumps import ParticleFrame
from ligwf.analysis.flow import DrumGeometry, frame_flow, profile_l2_error, summarise

R, D = 0.025, 0.001


def bed(angle_deg: float, axis: str = "y", omega: float = 3.0, rigid: bool = True,
        seed: int = 0) -> tuple[ParticleFrame, DrumGeometry]:
    """Particles filling the drum below a plane surface through the centre tilted by angle."""
    rng = np.random.default_rng(seed)
    pts = rng.uniform(-R, R, size=(20000, 2))
    t = math.radians(angle_deg)
    inside = (np.hypot(pts[:, 0], pts[:, 1]) < R - D) & (pts[:, 1] < np.tan(t) * pts[:, 0])
    uv = pts[inside]
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
@pytest.mark.parametrize("angle", [0.0, 20.0, 35.0])
def test_angle_of_repose_of_a_plane_surface(axis, angle):
    frame, geo = bed(angle, axis)
    f = frame_flow(frame, geo)
    assert f.angle_of_repose == pytest.approx(angle, abs=2.0)


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
