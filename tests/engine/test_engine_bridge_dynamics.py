"""The engine's viscous force and its bridges' life, measured on two particles.

Two particles are held (no integrator) and particle 2 is given a velocity or set along a
path of gaps; the engine's pair force on it is read from thermo after every step
(``render_bridge_probe``). Two facts are pinned here:

* the viscous force ligwf mirrors (:func:`~ligwf.liquids.capillary.viscous_normal_force`,
  :func:`~ligwf.liquids.capillary.viscous_tangential_force`) is the engine's, with
  ``liquid.min_separation_ratio`` below 1 (lubrication on) as at the default 1.01 (off);
* washino forms a bridge on approach at the gap where it breaks on separation (no
  hysteresis); easo forms one only once the pair has touched, and it then holds out to the
  same kind of end (the law's rupture gap or the cut at ``max_separation_ratio``, whichever
  is shorter: :func:`ligwf.scene.regime.bridge_gap_ratio`).
"""

from __future__ import annotations

import re

import numpy as np
import pytest

from ligwf.engine.render import render_bridge_probe
from ligwf.liquids.capillary import viscous_normal_force, viscous_tangential_force
from ligwf.scene.regime import bridge_gap_ratio
from ligwf.scene.scaling import scale
from ligwf.scene.workflow import load_workflow

from helpers import DRUM, run_liggghts

pytestmark = [pytest.mark.engine]

ROW = re.compile(r"^\s+\d+\s+2\s+\S+\s+\S+\s+\S+\s*$")
GAPS = (0.01, 0.03, 0.1, 0.3)     # surface gap / R*, all inside the bridge (ends at 0.4)
SPEED = 0.1                        # m/s


def scaled(model: str, *overrides: str):
    return scale(load_workflow(DRUM, [f"scene.liquid.model={model}", *overrides]).cases[0].scene,
                 1, "none")


def probe_path(engine, case, s, path, velocity=(0.0, 0.0, 0.0), touch_first=False):
    """(gap / R*, force on particle 2 along x, along y) after every step of ``path``;
    the pair starts at 0.9 R* (no bridge) or, ``touch_first``, touching and then at the
    path's first gap."""
    case.mkdir()
    start = path[0] if touch_first else 0.9
    files = render_bridge_probe(s, start, model_approach=touch_first, velocity=velocity,
                                path=path)
    (case / "in.liggghts").write_text(files["in.liggghts"])
    out = run_liggghts(engine, case, nprocs=1, timeout=120)
    assert out.returncode == 0, out.stdout[-3000:]
    rows = np.array([[float(w) for w in l.split()[2:]] for l in out.stdout.splitlines()
                     if ROW.match(l)])
    assert len(rows), out.stdout[-3000:]
    r_eff = 0.25 * s.d_min
    return rows[:, 0] / r_eff, rows[:, 1], rows[:, 2]


def at_gaps(gaps, values, wanted):
    """The last value recorded at each wanted gap ratio."""
    return np.array([values[np.flatnonzero(np.isclose(gaps, g, rtol=1e-6))[-1]] for g in wanted])


@pytest.mark.parametrize("model", ["washino", "easo"])
@pytest.mark.parametrize("s_min", [0.02, 0.05, 0.3, 1.01])
def test_engine_viscous_force_is_the_mirror(engine, tmp_path, model, s_min):
    """Particle 2 moves away (+x) or towards (-x) particle 1 at 0.1 m/s, and sideways (+y)
    at 0.1 m/s; half the difference of the x forces is the normal viscous force (the
    capillary force cancels), the y force the tangential one. Both equal the mirror to
    1e-6 at every gap, on both sides of s_min."""
    s = scaled(model, f"scene.liquid.min_separation_ratio={s_min}")
    assert s.liquid_values.min_separation_ratio == s_min
    touch = s.liquid.bridge_needs_contact     # easo's bridge needs the touch first
    path = [g * 0.25 * s.d_min for g in GAPS]
    r = 0.5 * s.d_min
    mu = s.liquid_values.viscosity
    g_out, fx_out, fy_out = probe_path(engine, tmp_path / "out", s, GAPS, (SPEED, SPEED, 0), touch)
    g_in, fx_in, _ = probe_path(engine, tmp_path / "in", s, GAPS, (-SPEED, SPEED, 0), touch)
    normal = 0.5 * (at_gaps(g_in, fx_in, GAPS) - at_gaps(g_out, fx_out, GAPS))
    tangential = -at_gaps(g_out, fy_out, GAPS)
    mirror_n = viscous_normal_force(r, r, np.array(path), mu, SPEED, s_min)
    mirror_t = viscous_tangential_force(r, r, np.array(path), mu, SPEED, s_min)
    assert normal == pytest.approx(mirror_n, rel=1e-6)
    assert tangential == pytest.approx(mirror_t, rel=1e-6)
    # the test tells lubrication from Stokes drag: below 1 the force grows as the gap closes
    if s_min < GAPS[-1]:
        assert normal[0] > 1.5 * normal[-1]
    else:
        assert normal == pytest.approx(normal[0], rel=1e-9)


APPROACH = [round(x, 4) for x in np.arange(0.70, -0.001, -0.01)]
SEPARATION = [round(x, 4) for x in np.arange(0.0, 0.7001, 0.01)]
CONTACT = -0.02                    # overlap of 0.02 R* between approach and separation


@pytest.fixture(scope="module")
def bridge_paths(engine, tmp_path_factory):
    """Both models with bridges cut at 1.1 x (r_i + r_j) (x_0 0.4 for both) and at 1.2
    (the laws' rupture gaps are shorter: washino 0.51, easo 0.56), each taken along the
    same path: from 0.7 R* to contact, then back out to 0.7 R*."""
    tmp = tmp_path_factory.mktemp("paths")
    out = {}
    for model in ("washino", "easo"):
        for cut in (1.1, 1.2):
            s = scaled(model, f"scene.liquid.max_separation_ratio={cut}")
            gaps, fx, _ = probe_path(engine, tmp / f"{model}-{cut}", s,
                                     APPROACH + [CONTACT] + SEPARATION)
            k = int(np.flatnonzero(np.isclose(gaps, CONTACT))[0])
            attraction = -fx   # attraction pulls particle 2 (at +x) towards -x
            out[(model, cut)] = (s, (gaps[:k], attraction[:k]), (gaps[k + 1:], attraction[k + 1:]))
    return out


def bridged(gaps, attraction):
    return gaps[(gaps > 0) & (attraction > 0)]


@pytest.mark.parametrize("cut", [1.1, 1.2])
def test_washino_forms_bridges_on_approach_without_hysteresis(bridge_paths, cut):
    s, (g_in, f_in), (g_out, f_out) = bridge_paths[("washino", cut)]
    x_0 = bridge_gap_ratio(s, 0.5 * s.d_min)
    assert abs(bridged(g_in, f_in).max() - x_0) < 0.011     # forms before contact, at x_0
    assert abs(bridged(g_out, f_out).max() - x_0) < 0.011   # breaks at the same gap
    # the same force at every gap either way: no hysteresis
    common = [g for g in SEPARATION if g > 0]
    assert at_gaps(g_in, f_in, common) == pytest.approx(at_gaps(g_out, f_out, common),
                                                        rel=1e-12, abs=0)


@pytest.mark.parametrize("cut", [1.1, 1.2])
def test_easo_forms_bridges_only_at_contact_and_holds_them_on_separation(bridge_paths, cut):
    s, (g_in, f_in), (g_out, f_out) = bridge_paths[("easo", cut)]
    x_0 = bridge_gap_ratio(s, 0.5 * s.d_min)
    assert not np.any(f_in[g_in > 0])                         # no force at all on approach
    held = bridged(g_out, f_out)
    assert abs(held.max() - x_0) < 0.011                      # breaks at x_0
    assert len(held) >= int(x_0 / 0.01) - 1                   # bridged all the way out
    assert not np.any(f_out[g_out > x_0 + 0.011])


def test_the_two_models_bridge_ends_differ_only_where_the_law_decides(bridge_paths):
    """With the cut at 1.1 both bridges end at 0.4 R*; at 1.2 at their laws' own rupture
    gaps, easo's longer (its bridge takes the caps' liquid, washino 5 % of both)."""
    ends = {k: bridged(*v[2]).max() for k, v in bridge_paths.items()}
    assert ends[("washino", 1.1)] == pytest.approx(ends[("easo", 1.1)], abs=1e-9)
    assert 0.45 < ends[("washino", 1.2)] < ends[("easo", 1.2)] - 0.02
