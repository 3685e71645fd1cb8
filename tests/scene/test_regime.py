"""Dimensionless numbers, the granulation warning of `ligwf check`, and control twins."""

from __future__ import annotations

import math

import pytest

from ligwf.cli.main import main
from ligwf.errors import ConfigError
from ligwf.scene.regime import GRANULATING_BOND, GRANULATING_ST_V, original_numbers, regime_numbers
from ligwf.scene.workflow import CONTROL_KEY, load_workflow

from helpers import ROOT

GRANULES = ROOT / "workflows" / "granules.yaml"


def _case(overrides=()):
    return load_workflow(GRANULES, list(overrides)).cases


def test_numbers_by_hand_and_under_both_rules():
    cases = _case(["sweep.cg_levels=[1, 2]", "scene.liquid.viscosity=0.001",
                   "scene.liquid.surface_tension=0.024"])
    cg1 = next(c for c in cases if c.cg == 1)
    n = regime_numbers(cg1.scaled())
    r, v = 0.75e-3, 2 * math.pi * 30 / 60 * 0.02      # 1.5 mm beads, 40 mm drum at 30 rpm
    assert n["stokes_viscous"] == pytest.approx(8 * 2500 * r * v / (9 * 1e-3), rel=1e-9)
    assert n["bond_granular"] == pytest.approx(
        3 * 0.024 * math.cos(math.radians(30)) / (4 * r * r * 2500 * 9.81), rel=1e-9)
    we = regime_numbers(next(c for c in cases if c.rule.value == "weber").scaled())
    bo = regime_numbers(next(c for c in cases if c.rule.value == "bond").scaled())
    # Weber keeps St_v and Ca, halves Bo_g at CG2; Bond keeps Bo_g, halves St_v
    assert we["stokes_viscous"] == pytest.approx(n["stokes_viscous"])
    assert we["bond_granular"] == pytest.approx(n["bond_granular"] / 2)
    assert bo["bond_granular"] == pytest.approx(n["bond_granular"])
    assert bo["stokes_viscous"] == pytest.approx(n["stokes_viscous"] / 2)
    assert original_numbers(next(c for c in cases if c.cg == 2)) == pytest.approx(n)


def test_check_warns_where_the_map_expects_no_granules(capsys):
    """No mapped regime passed every control criterion, so every granule analysis is
    warned: water-like viscosity (St_v ~ 105) and binder-like viscosity with weak cohesion
    (St_v 0.35, Bo_g 1.1) as 'no definition beat the control', the map's closest point
    (St_v 0.35, Bo_g 3.4) as such; a case without contact dumps is not warned."""
    assert main(["check", str(GRANULES), "--set", "scene.liquid.viscosity=0.001",
                 "--set", "scene.liquid.surface_tension=0.024"]) == 0
    out = capsys.readouterr()
    assert "granule analysis asked for, but St_v = 105, Bo_g = 1.13: no granule definition" in out.err
    row = next(line for line in out.out.splitlines() if line.startswith("│ cg1-none-r0 ")
               and "105" in line)
    assert row.rstrip().endswith("no │")
    assert main(["check", str(GRANULES), "--set", "scene.liquid.viscosity=0.3",
                 "--set", "scene.liquid.surface_tension=0.024"]) == 0
    assert "St_v = 0.349, Bo_g = 1.13: no granule definition" in capsys.readouterr().err
    assert GRANULATING_BOND <= 3.39 and GRANULATING_ST_V >= 0.349
    assert main(["check", str(GRANULES), "--set", "scene.liquid.viscosity=0.3",
                 "--set", "scene.liquid.surface_tension=0.072"]) == 0
    out = capsys.readouterr()
    assert "St_v = 0.349, Bo_g = 3.39 is the regime map's closest point" in out.err
    assert "closest (unproven)" in out.out
    assert main(["check", str(GRANULES), "--set", "scene.liquid.viscosity=0.001",
                 "--set", "scene.analysis.contact_dumps=false"]) == 0
    assert "granule analysis asked for" not in capsys.readouterr().err


def test_cohesionless_twin_keeps_everything_but_the_bridge_forces():
    cases = _case(["sweep.controls=[cohesionless]"])
    wet = next(c for c in cases if c.case_id == "cg1-none-r0")
    twin = next(c for c in cases if c.case_id == "cg1-none-r0_cohesionless")
    assert dict(twin.varied)["control"] == "cohesionless"
    a, b = wet.scaled(), twin.scaled()
    assert b.liquid_values.surface_tension == pytest.approx(a.liquid_values.surface_tension / 1000)
    assert b.liquid_values.viscosity == pytest.approx(a.liquid_values.viscosity / 1000)
    assert (a.fill, a.particles, a.numerics, a.contact_dumps) == (b.fill, b.particles,
                                                                   b.numerics, b.contact_dumps)
    assert a.liquid_values.liquid_content == b.liquid_values.liquid_content
    # granules.yaml: 2 CG1 seeds, each with its twin; 2 seeds of each CG2 rule
    assert sum(c.cg == 1 for c in cases) == 4 and sum(c.cg == 2 for c in cases) == 4
    assert sum(CONTROL_KEY in dict(c.varied) for c in cases) == 2


def test_controls_refused_on_a_dry_scene_and_at_a_missing_level():
    with pytest.raises(ConfigError, match="dry"):
        _case(["sweep.controls=[cohesionless]", "scene.liquid.model=none",
               "sweep.rules=[weber]", "scene.analysis.contact_dumps=false"])
    with pytest.raises(ConfigError, match="control_cg_levels"):
        _case(["sweep.controls=[cohesionless]", "sweep.control_cg_levels=[3]"])
    with pytest.raises(ConfigError, match="controls"):
        _case(["sweep.controls=[wet]"])


def test_check_warns_when_the_definition_never_beat_the_control(capsys):
    assert main(["check", str(GRANULES), "--set", "analysis.granules=communities"]) == 0
    assert "analysis.granules: communities: its granules never beat" in capsys.readouterr().err
    assert main(["check", str(GRANULES)]) == 0                     # granules.yaml: held
    assert "never beat" not in capsys.readouterr().err
