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
    ennis = 8 * 2500 * r * v / (9 * 1e-3)
    assert n["stokes_viscous_ennis"] == pytest.approx(ennis, rel=1e-9)
    # bridges cut at 1.1 x (r_i + r_j): x_0 = 0.1 * 2r / (r / 2) = 0.4 R*; lubrication off
    # (s_min 1.01): the engine's viscous impulse is Stokes drag over 0.4 R*, J = 0.4 / 1.01
    assert n["bridge_gap_ratio"] == pytest.approx(0.4, rel=1e-9)
    assert n["viscous_path_integral"] == pytest.approx(0.4 / 1.01, rel=1e-9)
    assert n["stokes_viscous"] == pytest.approx(ennis * 1.01 / 0.4, rel=1e-9)
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
    # the engine's St_v: Ennis's 105 over J = 0.4 / 1.01 (lubrication off)
    assert "granule analysis asked for, but St_v = 264, Bo_g = 1.13: no granule definition" in out.err
    row = next(line for line in out.out.splitlines() if line.startswith("│ cg1-none-r0 ")
               and "264" in line)
    assert row.rstrip().endswith("no │")
    assert main(["check", str(GRANULES), "--set", "scene.liquid.viscosity=0.3",
                 "--set", "scene.liquid.surface_tension=0.024"]) == 0
    assert "St_v = 0.881, Bo_g = 1.13: no granule definition" in capsys.readouterr().err
    assert GRANULATING_BOND <= 3.39 and GRANULATING_ST_V >= 0.881
    assert GRANULATING_ST_V < 2.64   # the map's next point (mu 0.1) stays outside
    assert main(["check", str(GRANULES), "--set", "scene.liquid.viscosity=0.3",
                 "--set", "scene.liquid.surface_tension=0.072"]) == 0
    out = capsys.readouterr()
    assert "St_v = 0.881, Bo_g = 3.39 is the regime map's closest point" in out.err
    assert "extrapolation" not in out.err
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
    # granules.yaml: 2 CG1 replicas, each with its twin; 2 replicas of each CG2 rule
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


def numbers(*overrides: str) -> dict[str, float]:
    case = next(c for c in _case(list(overrides)) if c.cg == 1)
    return regime_numbers(case.scaled())


@pytest.mark.parametrize("s_min", [0.02, 0.05, 0.3])
def test_engine_stokes_number_follows_the_lubrication_the_engine_applies(s_min):
    """Below the bridge's end (x_0 = 0.4 here) the engine's law is lubrication cut at
    s_min: J = 1 + ln(0.4 / s_min), so St_v = St_v,Ennis / J, smaller than with the
    default 1.01 by J(s_min) / J(1.01); Ennis's number does not move."""
    off, on = numbers(), numbers(f"scene.liquid.min_separation_ratio={s_min}")
    j = 1 + math.log(0.4 / s_min)
    assert on["viscous_path_integral"] == pytest.approx(j, rel=1e-9)
    assert on["stokes_viscous"] == pytest.approx(on["stokes_viscous_ennis"] / j, rel=1e-9)
    assert on["stokes_viscous_ennis"] == off["stokes_viscous_ennis"]
    assert on["stokes_viscous"] / off["stokes_viscous"] == pytest.approx(
        (0.4 / 1.01) / j, rel=1e-9)


def test_bridge_end_is_the_laws_rupture_when_the_cut_is_farther():
    """max_separation_ratio 1.3 puts the cut at 1.2 R*, beyond washino's rupture gap
    (1 + theta/2) V^(1/3), V = 0.05 x both particles' liquid: x_0 is the rupture gap."""
    n = numbers("scene.liquid.max_separation_ratio=1.3", "scene.liquid.min_separation_ratio=0.02")
    r, theta = 0.75e-3, math.radians(30)
    volume = 0.05 * 2 * 0.02 * 4 / 3 * math.pi * r**3
    x_0 = (1 + theta / 2) * volume ** (1 / 3) / (r / 2)
    assert 0.4 < x_0 < 1.2
    assert n["bridge_gap_ratio"] == pytest.approx(x_0, rel=1e-9)
    assert n["viscous_path_integral"] == pytest.approx(1 + math.log(x_0 / 0.02), rel=1e-9)


def test_engine_stokes_number_keeps_the_cg_rules():
    """x_0 and J are gap ratios, unchanged by CG: the engine's St_v is Weber-invariant and
    falls as 1/n under Bond scaling, as Ennis's does."""
    cases = _case(["sweep.cg_levels=[1, 2]", "scene.liquid.min_separation_ratio=0.02"])
    n1 = regime_numbers(next(c for c in cases if c.cg == 1).scaled())
    we = regime_numbers(next(c for c in cases if c.rule.value == "weber").scaled())
    bo = regime_numbers(next(c for c in cases if c.rule.value == "bond").scaled())
    assert we["viscous_path_integral"] == pytest.approx(n1["viscous_path_integral"], rel=1e-9)
    assert we["stokes_viscous"] == pytest.approx(n1["stokes_viscous"], rel=1e-9)
    assert bo["stokes_viscous"] == pytest.approx(n1["stokes_viscous"] / 2, rel=1e-9)


def test_warning_says_the_map_had_lubrication_off(capsys):
    """With lubrication on, mu 0.1 (St_v,Ennis 1.05, the map's 'no' point) falls to the
    engine's St_v 0.26, inside the closest region: the warning grades it so, and says the
    map never ran with lubrication on."""
    assert main(["check", str(GRANULES), "--set", "scene.liquid.viscosity=0.1",
                 "--set", "scene.liquid.surface_tension=0.072",
                 "--set", "scene.liquid.min_separation_ratio=0.02"]) == 0
    err = capsys.readouterr().err
    assert "St_v = 0.262, Bo_g = 3.39 is the regime map's closest point" in err
    assert "min_separation_ratio = 0.02 switches the engine's lubrication on" in err
    assert "extrapolation" in err


def test_dry_bed_has_no_bridge_numbers():
    from helpers import DRUM
    case = load_workflow(DRUM, ["scene.liquid.model=none", "scene.analysis.contact_dumps=false",
                                "sweep.rules=[weber]"]).cases[0]
    n = regime_numbers(case.scaled())
    assert n["stokes_viscous"] == math.inf and n["bond_granular"] == 0.0
    assert n["viscous_path_integral"] == 0.0


def test_lubrication_warning_quotes_the_screen_as_committed(capsys):
    """The screen's finding in the warning (issue 47 item 4) is what the committed table
    says: the pick's survival and co-movement, its wet share at start and end, and the
    uniform conditions bound into one slice-spanning mass."""
    import pandas as pd

    from ligwf.scene import regime
    from tests.helpers import ROOT

    cond = pd.read_csv(ROOT / "docs" / "results" / "granule_screen" / "conditions.csv")
    cond = cond.set_index("condition")
    pick = cond[cond["rank"] == 1].iloc[0]
    assert pick.name == "S3" and pick.liquid == "placed nuclei" and pick.model == "easo"
    for name in ("S2", "S4"):
        assert cond.loc[name, "wet_mass"] and cond.loc[name, "spanning_frames"] == 1.0
    assert cond.loc["S1", "status"] == "unstable"
    seeds = pd.read_csv(ROOT / "docs" / "results" / "granule_screen" / "phase2_seeds.csv")
    assert len(seeds) == 5 and seeds.complete.all()
    assert round(seeds.survival.mean(), 2) == regime.SCREEN_SURVIVAL
    assert round(seeds.comove_ratio.mean(), 2) == regime.SCREEN_COMOVEMENT
    assert round(seeds.share_10.mean(), 2) == regime.SCREEN_SHARE
    assert round(seeds.uniform_share_10.mean(), 2) == regime.SCREEN_UNIFORM_SHARE
    assert round(seeds.wet_share_start.mean(), 2) == regime.SCREEN_WET_START
    assert round(seeds.wet_share_end.mean(), 2) == regime.SCREEN_WET_END
    assert main(["check", str(GRANULES), "--set", "scene.liquid.viscosity=0.1",
                 "--set", "scene.liquid.surface_tension=0.072",
                 "--set", "scene.liquid.min_separation_ratio=0.02"]) == 0
    assert "found no growth" in " ".join(capsys.readouterr().err.split())
