"""Pre-flight stability checks: time scales against hand-computed values, verdicts,
refusal messages and the CLI hooks (no engine)."""

from __future__ import annotations

import math
import re
from pathlib import Path

import pytest

from ligwf import liquids
from ligwf.scene import stability as st
from ligwf.scene import timescales as ts
from ligwf.cli.main import main
from ligwf.engine.render import render
from ligwf.scene.scaling import scale
from ligwf.scene.stability_suite import load_suite
from ligwf.scene.workflow import load_workflow

ROOT = Path(__file__).resolve().parents[2]
SUITE = ROOT / "workflows" / "stability.yaml"
DRUM = ROOT / "tests" / "workflows" / "drum.yaml"

# Hand computation for r = 1 mm, rho = 2500 kg/m^3, E = 1e7 Pa, nu = 0.3:
#   G = E / 2.6 = 3.846e6 Pa; t_R = pi 1e-3 sqrt(2500 / 3.846e6) / (0.1631*0.3 + 0.8766)
#       = 3.1416e-3 * 0.025495 / 0.92553 = 8.654e-5 s
#   m = 4/3 pi 1e-9 2500 = 1.0472e-5 kg; E* = 1e7 / (2 * 0.91) = 5.4945e6 Pa
#   t_H(v = 1 m/s) = 2.87 (m^2 / (5e-4 E*^2 1))^(1/5) = 2.87 (1.0966e-10 / 1.5095e10)^(1/5)
#       = 2.87 * 9.381e-5 = 2.692e-4 s
#   delta(v = 1) = (15 (m/2) / (16 E* sqrt(5e-4)))^(2/5) = (7.854e-5 / 1.9658e6)^(2/5)
#       = (3.995e-11)^(2/5) = 6.928e-5 m
#   washino, 2 % liquid, theta = 0: V = 0.05 * 2 * 4.18879e-9 * 0.02 = 8.3776e-12 m^3,
#       F0 = 2 pi 5e-4 0.072 = 2.2619e-4 N, k_b = F0 sqrt(pi 5e-4 / (2 V)) = F0 * 9682.5
#       = 2.1901 N/m, t_c = sqrt((m/2) / k_b) = sqrt(5.236e-6 / 2.1901) = 1.5462e-3 s
R, RHO, E, NU = 1e-3, 2500.0, 1e7, 0.3


def test_rayleigh_time_hand_value():
    from ligwf.scene.scaled import rayleigh_time
    assert rayleigh_time(R, RHO, E, NU) == pytest.approx(8.654e-5, rel=2e-4)


def test_hertz_time_hand_value():
    assert ts.hertz_time(R, RHO, E, NU, 1.0) == pytest.approx(2.692e-4, rel=5e-4)


def test_hertz_overlap_hand_value():
    assert ts.hertz_max_overlap(R, RHO, E, NU, 1.0) == pytest.approx(6.928e-5, rel=5e-4)


def test_capillary_time_hand_value():
    f0, k_b = liquids.get("washino").contact_force_and_stiffness(R, 0.072, 0.0, 0.02)
    assert f0 == pytest.approx(2.2619e-4, rel=2e-4)
    assert k_b == pytest.approx(2.1901, rel=2e-4)
    m_eff = 0.5 * ts.sphere_mass(R, RHO)
    assert ts.capillary_time(m_eff, k_b) == pytest.approx(1.5462e-3, rel=2e-4)


def test_capillary_overlap_balances_hertz_and_collapses_when_pull_wins():
    f0, k_b = 1e-3, 10.0
    d = ts.capillary_overlap(R, E, NU, f0, k_b)
    e_star = ts.effective_modulus(E, NU)
    hertz = 4.0 / 3.0 * e_star * math.sqrt(0.5 * R) * d**1.5
    assert hertz == pytest.approx(f0 + k_b * d, rel=1e-9)
    assert math.isinf(ts.capillary_overlap(R, 1e5, NU, 10.0, 1e6))


def test_froude_regime_and_critical_speed_hand_values():
    # D = 0.1 m at 60 rpm: omega = 2 pi, Fr = 4 pi^2 0.05 / 9.81 = 0.2012 (cataracting);
    # n_c = 60/(2 pi) sqrt(9.81/0.05) = 133.76 rpm; v_imp = 2 pi 0.05 + sqrt(2 9.81 0.1)
    # = 0.3142 + 1.4007 = 1.7149 m/s
    assert ts.impact_velocity(2 * math.pi, 0.1) == pytest.approx(1.7149, rel=1e-4)
    assert ts.regime(0.2012) == "cataracting"
    assert ts.regime(1.5) == "centrifuging"
    assert ts.regime(0.02) == "cascading"
    assert ts.regime(1e-3) == "rolling"
    assert ts.regime(1e-5) == "slumping"
    wf = load_workflow(DRUM, ["scene.drum.diameter=0.1", "scene.process.rotation.rpm=60",
                              "scene.drum.lifters.count=0", "sweep.cg_levels=[1]"])
    sc = ts.time_scales(wf.cases[0].scaled())
    assert sc.froude == pytest.approx(0.2012, rel=1e-3)
    assert sc.critical_rpm == pytest.approx(133.76, rel=1e-4)
    assert sc.regime == "cataracting"


def test_demo_is_not_refused():
    wf = load_workflow(DRUM)
    for case in wf.cases:
        assert st.preflight(case.scaled(), case.case_id).verdict != st.REFUSED


REFUSAL = re.compile(r"^(?P<field>[a-z_.]+): .*= (?P<value>[0-9.e+-]+) .*limit (?P<limit>[0-9.e+%-]+)"
                     r".*; (?P<suggestion>(use|lower) .+)$")


def test_every_refusal_names_field_value_limit_and_suggestion():
    refusals = []
    for wf in load_suite(SUITE).values():
        for case in wf.cases:
            rep = st.preflight(case.scaled(), case.case_id,
                               explicit_dt=case.scene.numerics.dt is not None)
            refusals += [f for f in rep.findings if f.verdict == st.REFUSED]
    checks = {f.check for f in refusals}
    assert {"dt_rayleigh", "dt_hertz", "dt_capillary", "capillary_overlap"} <= checks
    for f in refusals:
        m = REFUSAL.match(f.message)
        assert m, f"refusal message lacks field/value/limit/suggestion: {f.message}"
        assert m["field"] == f.field


def test_refusal_message_example_shape():
    wf = load_workflow(DRUM, ["scene.numerics.dt=1.0e-4", "sweep.cg_levels=[3]",
                              "sweep.rules=[weber]"])
    case = wf.cases[0]
    rep = st.preflight(case.scaled(), case.case_id, explicit_dt=True)
    msg = next(f.message for f in rep.findings if f.check == "dt_rayleigh")
    t_r = case.scaled().particles.rayleigh_time
    assert msg.startswith(f"numerics.dt: dt = 0.0001 s is {1e-4 / t_r:.3g}x the Rayleigh time "
                          f"of the smallest CG3 particle ({t_r:.2g} s); limit 0.2x; "
                          f"use dt <= {0.2 * t_r:.2g} s")


def test_explicit_dt_overrides_the_fraction_and_is_reported():
    wf = load_workflow(DRUM, ["scene.numerics.dt=2.0e-6", "sweep.cg_levels=[1, 2]",
                              "sweep.rules=[weber]"])
    for case in wf.cases:
        s = case.scaled()
        assert s.numerics.dt == 2.0e-6
        assert s.numerics.dt_rayleigh_fraction == pytest.approx(2.0e-6 / s.particles.rayleigh_time)
    default = load_workflow(DRUM).cases[0].scaled()
    assert default.numerics.dt == pytest.approx(0.16 * default.particles.rayleigh_time)
    assert default.numerics.dt_rayleigh_fraction == 0.16


@pytest.mark.parametrize("modulus, line", [(1e10, "hard_particles yes"),
                                           (1e6, "soft_particles yes")])
def test_extreme_moduli_render_the_engine_switch(modulus, line):
    wf = load_workflow(DRUM, [f"scene.particles.youngs_modulus={modulus}",
                              "sweep.cg_levels=[1]"])
    text = render(wf.cases[0].scaled())["in.liggghts"]
    assert line in text.splitlines()
    normal = render(load_workflow(DRUM).cases[0].scaled())["in.liggghts"]
    assert "hard_particles" not in normal and "soft_particles" not in normal


def test_enforce_refuses_unless_overridden():
    wf = load_workflow(DRUM, ["scene.numerics.dt_rayleigh_fraction=0.5", "sweep.cg_levels=[1]"])
    reps = [st.preflight(c.scaled(), c.case_id) for c in wf.cases]
    with pytest.raises(st.UnstableCase, match="0.5x the Rayleigh time"):
        st.enforce(reps)
    warnings = st.enforce(reps, allow_unstable=True)
    assert any("allowed by --allow-unstable" in w for w in warnings)


def test_cli_check_and_render_refuse_and_override(tmp_path, capsys):
    bad = ["--set", "scene.numerics.dt_rayleigh_fraction=1.0", "--set", "sweep.cg_levels=[1]"]
    assert main(["check", str(DRUM), *bad]) == 2
    err = capsys.readouterr().err
    assert "UnstableCase" in err and "Rayleigh time" in err and "--allow-unstable" in err
    out = tmp_path / "study"
    assert main(["render", str(DRUM), *bad, "--out", str(out),
                 "--mesh-cache", str(tmp_path / "m")]) == 2
    assert not out.exists(), "a refused workflow must not be written"
    assert main(["check", str(DRUM), *bad, "--allow-unstable"]) == 0
    assert main(["render", str(DRUM), *bad, "--allow-unstable", "--out", str(out),
                 "--mesh-cache", str(tmp_path / "m")]) == 0
    assert (out / "cg1-none-r0" / "in.liggghts").is_file()


def test_suite_sweeps_every_axis_the_issue_asks_for():
    suite = load_suite(SUITE)
    scaled = {v: [c.scaled() for c in wf.cases] for v, wf in suite.items()}
    assert max(s.particles.youngs_modulus for s in scaled["stiffness"]) > 1e9
    gammas = [s.liquid_values.surface_tension for s in scaled["surface_tension"]]
    assert min(gammas) == 0.0 and max(gammas) >= 100 * 0.072
    assert max(s.drum.froude for s in scaled["rotation"]) > 1.0
    assert {(s.cg, s.rule) for s in scaled["coarse_graining"]} >= {(4.0, "weber"), (4.0, "bond")}
    contents = [s.liquid_values.liquid_content for s in scaled["liquid_content"]]
    assert min(contents) <= 1e-4 and max(contents) >= 0.2
    fractions = [s.numerics.dt_rayleigh_fraction for s in scaled["timestep"]]
    assert min(fractions) <= 0.05 and max(fractions) >= 1.5
    for cases in scaled.values():
        assert all(s.particles.count <= 300 for s in cases)


# ---- the viscous damping time (lubrication on: small s_min makes the damper stiff)
#   r = 1 mm, rho = 2500: m = 1.0472e-5 kg, m* = 5.236e-6 kg; R* = 5e-4 m
#   mu = 0.1 Pa s, s_min = 0.02: c = 6 pi 0.1 5e-4 / 0.02 = 4.7124e-2 N s/m
#   m* / c = 1.1111e-4 s
RUNNER_TINY = ROOT / "tests" / "workflows" / "runner_tiny.yaml"


def test_viscous_time_hand_value():
    assert ts.viscous_time(R, RHO, 0.1, 0.02) == pytest.approx(1.1111e-4, rel=2e-4)
    assert ts.viscous_time(R, RHO, 0.0, 0.02) == math.inf


def _viscous(viscosity: float):
    wf = load_workflow(RUNNER_TINY, [f"scene.liquid.viscosity={viscosity}",
                                     "scene.liquid.min_separation_ratio=0.02",
                                     "sweep.rules=[weber]"])
    rep = st.preflight(wf.cases[0].scaled(), wf.cases[0].case_id)
    return next(f for f in rep.findings if f.check == "dt_viscous")


@pytest.mark.parametrize("viscosity, ratio, verdict", [
    (1.0, 2.35, st.MARGINAL), (2.0, 4.7, st.MARGINAL), (4.0, 9.4, st.REFUSED),
    (0.1, 0.235, st.OK)])
def test_viscous_damping_is_graded_where_the_engine_was_measured(viscosity, ratio, verdict):
    """runner_tiny at CG3 (We: mu x 3), s_min 0.02: the engine ran 4.7 to the end and lost
    atoms at 9.4 (measured 2026-12-07); the pre-flight warns above 2 and refuses above 5."""
    f = _viscous(viscosity)
    assert f.value == pytest.approx(ratio, rel=0.01) and f.verdict == verdict
    if verdict != st.OK:
        assert "liquid.min_separation_ratio" in f.message and "use dt <=" in f.message


def test_lubrication_off_leaves_the_viscous_damper_resolved():
    wf = load_workflow(RUNNER_TINY, ["sweep.rules=[weber]"])       # s_min 1.01, 1 mPa s
    rep = st.preflight(wf.cases[0].scaled(), wf.cases[0].case_id)
    assert next(f for f in rep.findings if f.check == "dt_viscous").verdict == st.OK


@pytest.mark.engine
def test_a_refused_viscous_damper_loses_atoms_in_the_engine(engine, tmp_path):
    """The refusal is the engine's behaviour, not a guess: let through with
    --allow-unstable, the 9.4x case is marked unstable by the runner."""
    args = [str(RUNNER_TINY), "--set", "scene.liquid.viscosity=4",
            "--set", "scene.liquid.min_separation_ratio=0.02", "--set", "sweep.rules=[weber]",
            "--set", "scene.process.run_time=0.3", "--mesh-cache", str(tmp_path / "m")]
    assert main(["check", *args[:-2]]) == 2
    out = tmp_path / "visc"
    main(["run", *args, "--out", str(out), "--allow-unstable", "--np", "1"])
    import json
    manifest = json.loads((out / "cg3-weber-r0" / "manifest.json").read_text())
    assert manifest["status"] == "unstable", manifest.get("reason")
