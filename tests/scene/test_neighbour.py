"""Neighbour skin from the physics: what it covers, how it scales, the override, and where
the rendered inputs switch it (the bond statistics and forces being the same as with the old
fixed skin is measured by benchmarks/bench_skin.py on a real case)."""

from __future__ import annotations

import math

import pytest

from ligwf.engine.render import render
from ligwf.engine.resume import RestartFile, render_resume
from ligwf.scene import neighbour
from ligwf.scene.scaling import scale
from ligwf.scene.workflow import load_workflow

from helpers import DRUM, ROOT

WE_VS_BO = ROOT / "workflows" / "we_vs_bo.yaml"


def scene_of(path=WE_VS_BO, overrides=()):
    return load_workflow(path, list(overrides)).cases[0].scene


def test_skin_lets_the_fastest_particle_run_rebuild_steps_between_rebuilds():
    d, dt, v = 1e-3, 1e-5, 0.1
    skin = neighbour.skin_for_speed(v, dt, d)
    # a rebuild comes when a particle has moved half a skin
    assert 0.5 * skin / (v * dt) == pytest.approx(neighbour.REBUILD_STEPS)


@pytest.mark.parametrize("speed, ratio", [(1e-9, neighbour.SKIN_MIN_RATIO),
                                          (1e3, neighbour.SKIN_MAX_RATIO)])
def test_skin_is_clamped_in_smallest_diameters(speed, ratio):
    assert neighbour.skin_for_speed(speed, 1e-5, 2e-3) == pytest.approx(ratio * 2e-3)


def test_we_vs_bo_skin_is_the_measured_optimum_and_the_same_ratio_at_every_cg():
    scene = scene_of()
    ratios = []
    for cg in (1, 2, 3):
        s = scale(scene, cg, "weber")
        assert s.numerics.skin == pytest.approx(neighbour.turning_skin(s.drum.omega, 0.5 * s.drum.diameter,
                                                              s.numerics.dt, s.d_min))
        ratios.append(s.numerics.skin / s.d_min)
        # filling drops particles across the drum: a thicker skin, capped at 0.5 d
        assert s.skin_fill == pytest.approx(neighbour.SKIN_MAX_RATIO * s.d_min)
        assert s.skin_fill > s.numerics.skin
    assert ratios == pytest.approx([ratios[0]] * 3, rel=1e-9)
    # 2 x 50 steps x 2 x omega R x dt / d: 0.15 d on this scene (measured optimum 0.15-0.2 d)
    assert 0.12 < ratios[0] < 0.2


def test_faster_drum_gets_a_thicker_skin():
    slow = scale(scene_of(overrides=["scene.process.rotation.rpm=10"]), 2, "weber")
    fast = scale(scene_of(overrides=["scene.process.rotation.rpm=40"]), 2, "weber")
    assert fast.numerics.skin == pytest.approx(4 * slow.numerics.skin)


def test_override_gives_the_old_fixed_skin_everywhere():
    s = scale(scene_of(overrides=["scene.numerics.skin_ratio=0.5"]), 3, "weber")
    assert s.numerics.skin == pytest.approx(0.5 * s.d_min)
    assert s.skin_fill == pytest.approx(0.5 * s.d_min)
    text = render(s)["in.liggghts"]
    assert [l for l in text.splitlines() if l.startswith("neighbor")] == [
        f"neighbor {0.5 * s.d_min:.12g} bin"]


def _neighbor_lines(text):
    return [(i, float(l.split()[1])) for i, l in enumerate(text.splitlines())
            if l.startswith("neighbor ")]


def test_input_fills_with_the_fill_skin_then_turns_with_the_turning_skin():
    s = scale(scene_of(), 2, "weber")
    lines = render(s)["in.liggghts"].splitlines()
    found = _neighbor_lines("\n".join(lines))
    assert [v for _, v in found] == pytest.approx([s.skin_fill, s.numerics.skin], rel=1e-9)
    settle = lines.index('print "ligwf-phase settle"')
    first_fill = next(i for i, l in enumerate(lines) if l.startswith('print "ligwf-phase fill'))
    assert found[0][0] < first_fill and first_fill < found[1][0] < settle


@pytest.mark.parametrize("phase_step, skins", [("fill", ("fill", "turn")),
                                               ("settle", ("turn",)),
                                               ("production", ("turn",))])
def test_resume_uses_the_skin_of_the_phase_it_continues(phase_step, skins):
    s = scale(scene_of(), 2, "weber")
    step = {"fill": 1, "settle": s.insertion_steps + 1,
            "production": s.insertion_steps + s.numerics.settle_steps + 1}[phase_step]
    text = next(iter(render_resume(s, RestartFile("restart/restart_a.liggghts", step)).values()))
    want = {"fill": s.skin_fill, "turn": s.numerics.skin}
    assert [v for _, v in _neighbor_lines(text)] == pytest.approx([want[k] for k in skins],
                                                                  rel=1e-9)


def test_dry_drum_without_rotation_speed_still_gets_a_valid_skin():
    s = scale(scene_of(DRUM), 1, "none")
    assert neighbour.SKIN_MIN_RATIO * s.d_min <= s.numerics.skin <= neighbour.SKIN_MAX_RATIO * s.d_min
    assert math.isfinite(s.skin_fill)
