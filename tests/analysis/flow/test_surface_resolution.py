"""The angle of repose is measured at one physical resolution at every CG level: the same
curved free surface built of beads of 1, 2 and 3 mm gives the same angle, and the
estimator before 2026-12-07 (strips of each bead's 2 d on a grid started at -half, whose
last strip ran up to a strip width past +half, so the window grew with d) is shown to move
with the bead size alone on the same surfaces: the check catches a size-dependent
estimator."""

from __future__ import annotations

import math

import numpy as np
import pytest

from ligwf.analysis.flow import surface
from ligwf.analysis.flow.surface import fit_surface
from ligwf.scene.grains import strip_warning, study_strip, surface_strips
from ligwf.scene.model import Scene
from ligwf.yamlio import read_yaml_file
from helpers import ROOT

R = 0.05          # drum radius, m
SIZES = (0.001, 0.002, 0.003)


def bed(d: float, curvature: float, theta: float = 35.0) -> tuple[np.ndarray, ...]:
    """A bed whose free surface is the S-curve y = curvature x^3 (x along the mean
    surface, tilted by ``theta``): a dense row of beads with their tops on the curve, a
    square packing below it, inside the drum."""
    t = math.radians(theta)
    xs = np.arange(-R, R, d / 4)
    ys = curvature * xs ** 3 - d / 2
    gx, gy = (a.ravel() for a in np.meshgrid(np.arange(-R, R, d), np.arange(-R, 0, d)))
    below = gy < curvature * gx ** 3 - 1.5 * d
    x, y = np.concatenate([xs, gx[below]]), np.concatenate([ys, gy[below]])
    u, v = x * math.cos(t) - y * math.sin(t), x * math.sin(t) + y * math.cos(t)
    inside = u * u + v * v < (R - d / 2) ** 2
    return u[inside], v[inside], np.full(int(inside.sum()), d / 2)


def angles(curvature: float, strip: float | None) -> list[float]:
    return [fit_surface(*bed(d, curvature), R, d, +1.0, strip=strip).angle_deg for d in SIZES]


def size_dependence(curvature: float, strip: float | None) -> float:
    """Largest minus smallest angle over the bead sizes, deg."""
    a = angles(curvature, strip)
    return max(a) - min(a)


def former_strip_tops(x, top, width, half, gap):
    """The strips before 2026-12-07: a grid from -half, its last strip past +half."""
    edges = np.arange(-half, half + width, width)
    idx = np.digitize(x, edges) - 1
    xs, ys = [], []
    for k in range(len(edges) - 1):
        h = np.sort(top[idx == k])[::-1]
        if len(h) < 3:
            continue
        drops = np.flatnonzero(h[:-1] - h[1:] < gap)
        if len(drops):
            xs.append(0.5 * (edges[k] + edges[k + 1]))
            ys.append(h[drops[0]])
    return np.asarray(xs), np.asarray(ys)


def test_a_flat_surface_is_measured_exactly_at_every_size():
    for strip in (None, study_strip([*SIZES])):
        assert angles(0.0, strip) == pytest.approx([35.0] * 3, abs=1e-5)


@pytest.mark.parametrize("curvature", [30.0, 60.0, 120.0])
def test_one_resolution_gives_one_angle_on_a_curved_surface(curvature):
    strip = study_strip([*SIZES])            # twice the coarsest diameter: 6 mm
    assert strip == pytest.approx(0.006)
    assert size_dependence(curvature, strip) < 0.1


@pytest.mark.parametrize("curvature", [60.0, 120.0])
def test_the_former_estimator_moves_with_the_bead_size(curvature, monkeypatch):
    """The former rule (2 d strips, window growing with d) on the same surfaces: the check
    above fails for it, so it would catch a size-dependent estimator."""
    monkeypatch.setattr(surface, "_strip_tops", former_strip_tops)
    assert size_dependence(curvature, None) > 0.2


def test_study_strip_setting():
    assert study_strip([0.001, 0.004]) == pytest.approx(0.008)
    assert study_strip([0.001, 0.004], 0.01) == pytest.approx(0.01)
    assert study_strip([0.001, 0.004], 0.0) is None       # 0: each case's own diameter
    assert study_strip([]) is None


def _scene(name: str) -> Scene:
    return Scene.model_validate(read_yaml_file(ROOT / "workflows" / name, "workflow")["scene"])


def test_check_warns_when_the_one_resolution_leaves_too_few_strips():
    """The demo drum at CG4 (8 mm beads, 50 mm drum): 16 mm strips leave 2; the source drum
    at CG8 (16 mm strips in 0.2 m) leaves plenty."""
    demo = _scene("extrapolation_demo_drum.yaml")
    assert surface_strips(demo, 0.016) == 2
    assert "2 strips, fewer than the 4" in strip_warning(demo, 0.016)
    assert strip_warning(demo, 0.004) is None and strip_warning(demo, None) is None
    assert surface_strips(_scene("paper_scale_cg.yaml"), 0.016) >= 8
