"""Cross-section fields (ligwf.analysis.flow.fields) on synthetic frames with known fields.

A rigid rotation omega x r of particles on a square lattice filling the lower half of a
disc: the solid fraction is known from the lattice (V per site over a^2 L), the velocity
field is linear and the granular temperature zero. Kernel: Gaussian of std w = 2 mm
(cut at 3 w), nodes every w / 2. "Interior" nodes are more than 3 w + a from the edge
of the material (the kernel sees only material there), so the tolerances are set by
the deposit, not by the edge: a linear field is reproduced exactly by a symmetric
kernel, and the cloud-in-cell tent widens the kernel by 2 % (no effect on a linear
field). A lattice (unlike a random bed) beats with the node grid: its frequency 1/a
aliases to |1/a - k/h|, damped by the Gaussian as exp(-(2 pi w f)^2 / 2); the lattice
spacings (1.5 mm and 3 mm on nodes every 1 mm) put that beat at f >= 1/3 per mm, damped
below 2e-4, so the interior solid fraction is exact to 1e-3.
"""

from __future__ import annotations

import dataclasses
import math
from pathlib import Path

import numpy as np
import pytest

from ligwf.analysis.flow.fields import (case_fields, field_grid, flux_moments,
                                        fluctuation_moment, kernel_width, mean_velocity,
                                        reference_moments)
from ligwf.analysis.flow.frame import DrumGeometry
from ligwf.analysis.frames.dumps import ParticleFrame
from ligwf.inference.field_errors import (field_floor, field_interval, layer_error,
                                                 solid_error, whole_windows)
from ligwf.analysis.records.fields import fields_bytes, fields_of, image_text, read_fields
from ligwf.errors import ConfigError
from ligwf.scene.settings import build_analysis_settings

OMEGA = 3.0          # rad/s about +y
DRUM_R = 0.06        # m
BED_R = 0.05         # m, the lattice fills the disc of this radius below the axis
LENGTH = 0.004       # m, periodic length
D1 = 0.001           # m, CG1 diameter
WIDTH = 2 * D1       # m, kernel std (field_kernel 2)
HEAD = dict(cg=1.0, rule="none", replica=0, group="{}")


def lattice_frame(d: float, spacing: float, per_site: int, step: int = 0,
                  noise: float = 0.0, seed: int = 0, scale: float = 1.0) -> ParticleFrame:
    """Particles of diameter d on a square lattice (spacing m) in the lower half disc,
    ``per_site`` of them along the axis, moving as omega x r (times ``scale``) plus
    Gaussian noise of std ``noise`` m/s per component."""
    g = np.arange(-BED_R, BED_R + 1e-12, spacing)
    uu, vv = np.meshgrid(g, g)
    keep = (uu**2 + vv**2 <= BED_R**2) & (vv <= 0)
    u, v = uu[keep], vv[keep]
    ys = (np.arange(per_site) + 0.5) * LENGTH / per_site
    p = np.stack([np.repeat(u, per_site), np.tile(ys, len(u)), np.repeat(v, per_site)], axis=1)
    vel = scale * np.cross(np.array([0.0, OMEGA, 0.0]), p)
    if noise:
        vel = vel + np.random.default_rng(seed).normal(0.0, noise, vel.shape)
    n = len(p)
    return ParticleFrame(Path(f"synthetic_{step}.vtu"), step, step * 1e-3,
                         np.arange(1, n + 1), np.ones(n, np.int32), p, vel,
                         np.full(n, 0.5 * d), None)


def geometry(d: float) -> DrumGeometry:
    return DrumGeometry(radius=DRUM_R, axis="y", omega=OMEGA, d_mean=d)


def interior(grid, spacing: float) -> np.ndarray:
    """Nodes whose kernel (3 w) sees only the lattice (one lattice spacing of margin)."""
    x = grid.coordinates()
    uu, vv = np.meshgrid(x, x)
    margin = 3 * grid.width + spacing
    return (np.hypot(uu, vv) <= BED_R - margin) & (vv <= -margin)


def rotation_fields(d: float, spacing: float, per_site: int, cg: float, frames: int = 1):
    geo = geometry(d)
    width = kernel_width(geo, cg, 2.0)
    fr = [lattice_frame(d, spacing, per_site, step=k) for k in range(frames)]
    return case_fields(fr, geo, width, LENGTH, {**HEAD, "case_id": f"cg{cg:g}", "cg": cg})


def test_rigid_rotation_recovered_within_kernel_resolution():
    spacing = 1.5e-3
    cf = rotation_fields(D1, spacing, 2, 1.0)
    f = fields_of(cf.mean())
    inside = interior(cf.grid, spacing)
    assert inside.sum() > 200
    phi_true = 2 * (math.pi * D1**3 / 6) / (spacing**2 * LENGTH)
    assert np.allclose(f["solid_fraction"][inside], phi_true, rtol=1e-3)
    x = cf.grid.coordinates()
    uu, vv = np.meshgrid(x, x)
    # omega e_y x (u, ., v) with u = x, v = z: (omega v, ., -omega u)
    assert np.allclose(f["velocity_u"][inside], OMEGA * vv[inside], atol=1e-3 * OMEGA * BED_R)
    assert np.allclose(f["velocity_v"][inside], -OMEGA * uu[inside], atol=1e-3 * OMEGA * BED_R)
    # T ~ 0: its square root below 0.3 % of the rim speed (bilinear velocity at the
    # particles, float round-off)
    assert np.nanmax(f["temperature"][inside]) < 1e-5 * (OMEGA * BED_R) ** 2
    # no material far above the bed: no velocity there
    assert np.isnan(f["velocity_u"][vv > 3 * WIDTH + spacing]).all()
    # the whole volume is on the grid: sum phi dA L = sum V
    total = f["solid_fraction"].sum() * cf.grid.spacing**2 * LENGTH
    assert total == pytest.approx(cf.frames and len(lattice_frame(D1, spacing, 2).ids)
                                  * math.pi * D1**3 / 6, rel=1e-9)


def test_cg_invariance_particles_twice_as_large():
    """The same rotation sampled by particles 2x larger (1 per site on a 2x lattice: the
    same solid fraction) gives the same fields: the kernel is the same physical width."""
    s1 = 1.5e-3
    cg1 = rotation_fields(D1, s1, 2, 1.0)
    cg2 = rotation_fields(2 * D1, 2 * s1, 1, 2.0)
    assert cg1.grid == cg2.grid
    f1, f2 = fields_of(cg1.mean()), fields_of(cg2.mean())
    inside = interior(cg1.grid, 2 * s1)
    assert inside.sum() > 100
    # both lattices beat with the grid at the 1e-3 level (module docstring): 3e-3
    assert np.allclose(f2["solid_fraction"][inside], f1["solid_fraction"][inside], rtol=3e-3)
    for k in ("velocity_u", "velocity_v"):
        assert np.allclose(f2[k][inside], f1[k][inside], atol=1e-3 * OMEGA * BED_R)
    assert solid_error(cg1.mean(), cg2.mean()) < 0.05


def test_granular_temperature_of_known_noise():
    """Isotropic noise of std s per component about the rotation: T = s^2 in the interior
    (over many frames, within 5 %)."""
    geo, spacing, s = geometry(D1), 1.5e-3, 0.02
    frames = [lattice_frame(D1, spacing, 2, step=k, noise=s, seed=k) for k in range(20)]
    cf = case_fields(frames, geo, WIDTH, LENGTH, {**HEAD, "case_id": "noisy"})
    t = fields_of(cf.mean())["temperature"][interior(cf.grid, spacing)]
    assert np.mean(t) == pytest.approx(s**2, rel=0.05)


def test_fast_deposit_matches_direct_kernel_sum():
    frame = lattice_frame(D1, 2.5e-3, 1, noise=0.05, seed=3)
    geo = geometry(D1)
    grid = field_grid(DrumGeometry(DRUM_R, "y", OMEGA, 4 * D1), 4 * WIDTH, LENGTH)
    fast, slow = flux_moments(frame, geo, grid), reference_moments(frame, geo, grid)
    # the cloud-in-cell tent widens the kernel by ~2 %: percent-level differences only
    assert np.abs(fast - slow).max() < 0.02 * np.abs(slow).max()
    vel = mean_velocity(fast)
    a, b = fluctuation_moment(frame, geo, grid, vel), reference_moments(frame, geo, grid, vel)
    assert np.abs(a - b).max() < 0.03 * np.abs(b).max()


def test_solid_error_interval_and_floor():
    """A CG-n bed whose solid fraction is 1.1 times CG1's everywhere (the CG1 sums with
    phi scaled): solid error 0.1, an interval that holds it; two CG1 runs of one lattice
    (the noise is in the velocities only): a measured floor of 0."""
    geo, spacing = geometry(D1), 2e-3

    def case(cid, replica, seed, cg=1.0):
        fr = [lattice_frame(D1, spacing, 4, step=k, noise=0.05, seed=seed + k)
              for k in range(12)]
        return case_fields(fr, geo, WIDTH, LENGTH, {**HEAD, "case_id": cid, "cg": cg,
                                                    "replica": replica})
    ref = [case("cg1-r0", 0, 0), case("cg1-r1", 1, 100)]
    m = ref[0].moments.copy()
    m[:, 0] *= 1.1
    dense = [dataclasses.replace(ref[0], case_id="cg2-r0", cg=2.0, moments=m),
             dataclasses.replace(ref[1], case_id="cg2-r1", cg=2.0, moments=m.copy())]
    assert float(solid_error(ref[0].mean(), dense[0].mean())) == pytest.approx(0.1, rel=1e-9)
    iv = field_interval(dense, ref, "field_solid_error", 200, 1)
    assert iv.lo <= iv.value <= iv.hi and iv.replicas == 2
    assert iv.value == pytest.approx(0.1, abs=1e-9)
    floor = field_floor(ref, "field_solid_error")
    assert floor.source == "measured over 2 CG1 replicas" and floor.value == 0.0
    one = field_floor(ref[:1], "field_solid_error")
    assert one.source.startswith("indicative: split-half") and one.value == 0.0
    assert math.isnan(field_interval(dense, [], "field_solid_error", 10, 1).value)


def test_window_means_at_every_criterion_width():
    """The analysis keeps the in-plane window means at 1, 2 and 4 CG1 diameters (and the
    drum's omega and radius); a rigid rotation has no flowing layer: no criterion."""
    cf = rotation_fields(D1, 2e-3, 1, 1.0, frames=4)
    assert [w.kernel for w in cf.window_means] == [1.0, 2.0, 4.0]
    assert cf.omega == OMEGA and cf.radius == DRUM_R
    for w in cf.window_means:
        assert w.grid.width == pytest.approx(w.kernel * D1)
        assert w.sums.shape == (3, 3, w.grid.nodes, w.grid.nodes)
    at2 = cf.at_kernel(2.0)
    assert at2.grid == cf.grid and np.allclose(at2.part("window"), cf.mean()[:3])
    assert math.isnan(layer_error(whole_windows([cf]), whole_windows([cf]), 2.0).value)


def test_archive_and_paraview_image_round_trip(tmp_path):
    pv = pytest.importorskip("pyvista")
    cf = rotation_fields(D1, 2e-3, 1, 1.0, frames=3)
    path = tmp_path / "f.npz"
    path.write_bytes(fields_bytes([cf]))
    assert fields_bytes([cf]) == path.read_bytes()     # deterministic: no time stamps
    back = read_fields(path)["cg1"]
    assert back.grid == cf.grid and list(back.steps) == [0, 1, 2]
    assert back.omega == OMEGA and back.radius == DRUM_R
    assert [w.kernel for w in back.window_means] == [1.0, 2.0, 4.0]
    assert all(a.grid == b.grid and np.allclose(a.sums, b.sums, rtol=1e-6, atol=1e-9)
               for a, b in zip(back.window_means, cf.window_means))
    assert np.allclose(back.moments, cf.moments, rtol=1e-6, atol=1e-9)
    img = tmp_path / "f.vti"
    img.write_text(image_text(cf))
    mesh = pv.read(img)
    assert mesh.dimensions == (cf.grid.nodes, 1, cf.grid.nodes)
    phi = np.asarray(mesh.point_data["solid_fraction"]).reshape(cf.grid.nodes, cf.grid.nodes)
    assert np.allclose(phi, fields_of(cf.mean())["solid_fraction"], rtol=1e-6)
    # point (x = u, z = v) of the image carries the rotation's velocity there
    vel = np.asarray(mesh.point_data["velocity"]).reshape(cf.grid.nodes, cf.grid.nodes, 3)
    inside = interior(cf.grid, 2e-3)
    x = cf.grid.coordinates()
    uu, vv = np.meshgrid(x, x)
    assert np.allclose(vel[..., 2][inside], -OMEGA * uu[inside], atol=1e-3 * OMEGA * BED_R)


@pytest.mark.parametrize("value", [0.1, -2, "wide", float("inf")])
def test_bad_kernel_width_refused_in_one_line(value):
    with pytest.raises(ConfigError) as exc:
        build_analysis_settings({"field_kernel": value})
    lines = [ln for ln in str(exc.value).splitlines()[1:] if ln.strip()]
    assert len(lines) == 1
    assert "analysis.field_kernel" in lines[0] and repr(value)[:3] in lines[0]


def test_kernel_width_is_physical():
    assert kernel_width(geometry(D1), 1.0, 2.0) == pytest.approx(2e-3)
    assert kernel_width(geometry(3 * D1), 3.0, 2.0) == pytest.approx(2e-3)
    with pytest.raises(ValueError, match="kernel width"):
        field_grid(geometry(D1), 0.0, LENGTH)
