"""What would decide the field criterion (ligwf.inference.deciding.field_plan): from its noise
pieces, the cheapest arm to add replicas to, halving (a round) and deciding (the report),
checked against the bounds LayerNoise itself predicts."""

from __future__ import annotations

import math

import pytest

from ligwf.inference.field_errors import FIELD_NOISE_COLUMNS, LayerNoise
from ligwf.inference.sampling import REPLICAS
from ligwf.inference.deciding import field_plan

ALPHA = 0.05


def row(distance, run_var, ref_var, runs=3, ref_runs=2) -> dict:
    return dict(zip(FIELD_NOISE_COLUMNS, (distance, run_var, ref_var, runs, ref_runs)))


def test_the_noisy_arm_gets_the_replicas_and_the_plan_decides():
    """CG1 noise 50x the CG-n noise, a CG1 replica 3x the price of a CG-n one: the plan
    still adds CG1 runs, and its predicted bounds decide against the budget."""
    r = row(0.15, 1e-5, 5e-4)
    out = field_plan(r, 0.10, ALPHA, (100.0, 300.0))
    assert out["round_by"] == REPLICAS and out["round_arm"] == "CG1"
    noise = LayerNoise(0.15, 1e-5, 5e-4, 3, 2)
    add = (int(out["decide_amount"]), int(out["decide_amount_cg1"]))
    h = noise.half_width(ALPHA, add)
    assert out["decide_half_width"] == pytest.approx(h)
    assert 0.15 - h > 0.10                                         # predicted: a fail
    fewer = (add[0], add[1] - 1) if add[1] else (add[0] - 1, add[1])
    assert 0.15 - noise.half_width(ALPHA, fewer) <= 0.10           # and the fewest that do
    halved = (int(out["round_amount"]), int(out["round_amount_cg1"]))
    assert noise.half_width(ALPHA, halved) <= 0.5 * noise.half_width(ALPHA)
    assert out["decide_core_hours"] == pytest.approx((add[0] * 100 + add[1] * 300) / 3600)


def test_the_arm_whose_noise_dominates_gets_the_replicas():
    """Mirror image of the first test: CG-n noise dominant, CG-n replicas the cheap ones."""
    out = field_plan(row(0.08, 3e-3, 1e-5, 3, 3), 0.10, ALPHA, (10.0, 1000.0))
    assert out["round_arm"] == "CG-n" and out["round_amount_cg1"] == 0


def test_no_plan_without_two_runs_per_arm_or_without_costs():
    assert field_plan(row(0.15, math.nan, 5e-4, 1, 2), 0.1, ALPHA, (1.0, 1.0)) == {}
    assert field_plan(row(0.15, 1e-4, 5e-4), 0.1, ALPHA, (math.nan, math.nan)) == {}


def test_layer_noise_bounds_are_the_criterions():
    """LayerNoise.estimate is the criterion as it was: sqrt(max(0, D^2 - S)) and D +- t sqrt(S)."""
    n = LayerNoise(0.2, 4e-4, 2e-4, 3, 2)
    s = 4e-4 / 3 + 2e-4 / 2
    e = n.estimate(ALPHA)
    assert e.value == pytest.approx(math.sqrt(0.04 - s))
    assert e.hi - 0.2 == pytest.approx(0.2 - e.lo) == pytest.approx(n.half_width(ALPHA))
    assert n.half_width(0.01) > n.half_width(0.05)
