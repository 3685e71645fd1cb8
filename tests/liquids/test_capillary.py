"""The LIGGGHTS capillary models (washino, easo): their forces scale as the CG rules say."""

from __future__ import annotations

import pytest

from ligwf.scene.scaling import Rule
from ligwf.scene.workflow import load_workflow

from helpers import DRUM
from liquid_checks import assert_forces_scale_as_rule


@pytest.mark.parametrize("model", ["washino", "easo"])
@pytest.mark.parametrize("n", [2, 3, 4])
@pytest.mark.parametrize("rule,power", [(Rule.WEBER, 2), (Rule.BOND, 3), (Rule.NONE, 1)])
def test_bridge_force_scales_as_rule(model, n, rule, power):
    scene = load_workflow(DRUM, [f"scene.liquid.model={model}"]).cases[0].scene
    assert_forces_scale_as_rule(scene, n, rule, power)


@pytest.mark.parametrize("model", ["washino", "easo"])
@pytest.mark.parametrize("s_min", [0.02, 0.05])
@pytest.mark.parametrize("rule,power", [(Rule.WEBER, 2), (Rule.BOND, 3)])
def test_lubrication_scales_as_rule(model, s_min, rule, power):
    """With lubrication on (s_min below the bridged gaps) the viscous force still scales
    as the rule says: s_min is a gap over R*, unchanged by CG, like every gap ratio."""
    scene = load_workflow(DRUM, [f"scene.liquid.model={model}",
                                 f"scene.liquid.min_separation_ratio={s_min}"]).cases[0].scene
    assert_forces_scale_as_rule(scene, 2, rule, power)
