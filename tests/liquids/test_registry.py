"""ligwf.liquids: the registry, and the LIGGGHTS property names checked on the Python side."""

from __future__ import annotations

import pytest

from ligwf import liquids
from ligwf.liquids.washino import WASHINO, Washino


def test_builtin_models_and_unknown_name():
    assert {"washino", "easo", "none"} <= set(liquids.names())
    assert not liquids.get("none").wet and liquids.get("easo").wet
    with pytest.raises(ValueError, match=r"unknown liquid model 'glue' \(allowed: .*easo.*\)"):
        liquids.get("glue")


def test_a_name_is_registered_once():
    assert liquids.register(WASHINO) is WASHINO             # the same object again: no-op
    with pytest.raises(ValueError, match="already registered"):
        liquids.register(Washino())


def test_property_names_are_checked():
    # LIGGGHTS accepts a misspelled property silently and fails only on a missing one
    with pytest.raises(ValueError, match="surfaceTensoin"):
        WASHINO.property_line("lq_gamma", "surfaceTensoin", "scalar", 0.07)
    one = (WASHINO.property_line("lq_gamma", "surfaceTension", "scalar", 0.07),)
    with pytest.raises(ValueError, match="needs each of"):
        WASHINO.checked_lines(one)
