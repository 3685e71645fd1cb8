"""The 2-D decomposition (issue #24): bed shares of uniform columns, the grid cost model,
the planner beyond the axial slabs and the runner using the planner's grid; the per-rank
atom / ghost counts parsed from a LIGGGHTS log. No engine."""

from __future__ import annotations

import pytest

from helpers import ROOT
from ligwf.engine.decomposition import (MIN_AXIAL_SLAB, Bed, axial_slab_limit, best_grid,
                                        column_shares, grid_cost, runner_grid)
from ligwf.engine.ghosts import last_run_spread, run_spreads
from ligwf.engine.plan import (BOUND_GRID, MIN_GRID_EFFICIENCY, MIN_MARGINAL_EFFICIENCY,
                               CaseLoad, case_grid,
                               case_load, efficiency, estimated_seconds, plan_ranks)
from ligwf.engine.render import processor_grid
from ligwf.errors import ConfigError
from ligwf.scene.workflow import load_workflow

PAPER = ROOT / "workflows" / "paper_scale.yaml"
PAPER_BED = Bed(0.2, 0.17, 0.001)


def paper(bed: Bed | None = PAPER_BED) -> CaseLoad:
    return CaseLoad("cg1", 360_000, 704_766, 0.06, 0.001, True, bed)


# ------------------------------------------------------------------ the bed across the drum

@pytest.mark.parametrize("columns", [1, 2, 3, 5, 8, 17, 40])
def test_column_shares_hold_the_whole_bed(columns):
    shares = column_shares(PAPER_BED, columns)
    assert len(shares) == columns and sum(shares) == pytest.approx(1.0)
    assert min(shares) >= 0.0


def test_a_flat_bed_splits_evenly_in_two_and_a_tilted_one_does_not():
    flat = column_shares(Bed(0.05, 0.3, 0.001, surface_deg=0.0), 2)
    assert flat == pytest.approx((0.5, 0.5), abs=1e-3)
    # measured on a turning bed (the We-vs-Bo drum, ~30 % fill): 82/18 % on 2 columns
    assert sorted(column_shares(Bed(0.05, 0.3, 0.001), 2)) == pytest.approx([0.18, 0.82],
                                                                           abs=0.03)


def test_bad_bed_values_are_refused_naming_the_field():
    for kwargs, field in (({"fill_fraction": 0.0}, "fill_fraction"),
                          ({"fill_fraction": 1.2}, "fill_fraction"),
                          ({"drum_diameter": -1.0}, "drum_diameter"),
                          ({"surface_deg": 95.0}, "surface_deg")):
        args = {"drum_diameter": 0.2, "fill_fraction": 0.17, "d_max": 0.001, **kwargs}
        with pytest.raises(ConfigError, match=f"bed {field} = .*allowed range"):
            Bed(**args)


# ------------------------------------------------------------------ the grid and its cost

def test_the_cost_model_is_calibrated_on_the_two_rank_measurement():
    # 11,963 CG1 particles of 1 mm in 18 mm kept 0.88 of the ideal on 2 axial ranks
    assert grid_cost(0.018, 0.001, True, None, 2, 1).efficiency == pytest.approx(0.88, abs=0.005)


def test_uniform_columns_cost_what_the_bed_leaves_them():
    one, two = (grid_cost(0.06, 0.001, True, PAPER_BED, 1, c) for c in (1, 2))
    assert one.efficiency == 1.0 and one.imbalance == 1.0
    assert two.imbalance == pytest.approx(2 * max(column_shares(PAPER_BED, 2)))
    assert two.efficiency < 1 / two.imbalance


@pytest.mark.parametrize("ranks", [1, 2, 4, 15, 30, 64, 119, 120, 256])
def test_grids_keep_slabs_and_columns_of_four_diameters_axial_first(ranks):
    g = best_grid(ranks, 0.06, 0.001, True, PAPER_BED)
    assert g.axial * g.across == ranks
    assert 0.06 / g.axial >= MIN_AXIAL_SLAB * 0.001 * (1 - 1e-9)
    assert PAPER_BED.box_width / g.across >= MIN_AXIAL_SLAB * 0.001 * (1 - 1e-9)
    assert g.axial == max(a for a in range(1, axial_slab_limit(0.06, 0.001) + 1)
                          if ranks % a == 0 and ranks // a <= PAPER_BED.across_limit)


def test_a_rank_count_no_grid_fits_is_refused():
    small = Bed(0.04, 0.3, 0.003)          # a 40 mm drum of 3 mm beads: 4 columns at most
    with pytest.raises(ConfigError, match="ranks = 7: no processor grid"):
        best_grid(7, 0.009, 0.003, True, small)


# ------------------------------------------------------------------ the planner beyond the slabs

def test_paper_scale_cg1_goes_past_the_slabs_onto_two_nodes():
    slabs = plan_ranks(paper(bed=None), None)              # cross-section unknown: as before
    assert (slabs.ranks, slabs.bound, slabs.grid) == (15, "slab", (15, 1))
    plan = plan_ranks(paper(), None)
    assert plan.ranks >= 64 and -(-plan.ranks // 64) >= 2
    assert plan.bound.startswith(BOUND_GRID) and plan.grid[1] > 1
    assert plan.grid[0] * plan.grid[1] == plan.ranks
    assert MIN_GRID_EFFICIENCY <= plan.efficiency < 1
    assert plan.estimated_seconds < slabs.estimated_seconds / 2
    assert plan.estimated_seconds == estimated_seconds(paper(), plan.ranks)


def test_more_cores_never_make_the_plan_slower_and_cores_cap_it():
    times = []
    for cores in (15, 32, 64, 128, None):
        p = plan_ranks(paper(), cores)
        assert cores is None or p.ranks <= cores
        times.append(p.estimated_seconds)
    assert times == sorted(times, reverse=True)


def test_small_cases_keep_their_plans():
    # the measured local plans do not change: 2 axial ranks for the 18 mm CG1, 1 for CG3
    cg1 = CaseLoad("c", 11_963, 10_000, 0.018, 0.001, True, Bed(0.05, 0.3, 0.001))
    assert (plan_ranks(cg1, 2).ranks, plan_ranks(cg1, 2).grid) == (2, (2, 1))
    assert efficiency(cg1, 2) == pytest.approx(0.88, abs=0.01)
    few = CaseLoad("c", 443, 10_000, 0.009, 0.003, True, Bed(0.05, 0.3, 0.003))
    assert plan_ranks(few, 2).ranks == 1
    # one slab but many particles: 2 columns across are slower than 2 slabs would be
    # (measured 1.4x: 0.88 / 1.4 = 0.63 of the ideal) and buy only ~14 % over 1 rank:
    # the second rank adds less than MIN_MARGINAL_EFFICIENCY, the case stays on 1
    many = CaseLoad("c", 13_333, 10_000, 0.009, 0.003, True, Bed(0.05, 0.3, 0.003))
    assert efficiency(many, 2) == pytest.approx(0.88 / 1.4, abs=0.08)
    assert estimated_seconds(many, 2) < estimated_seconds(many, 1)
    gain = estimated_seconds(many, 1) / estimated_seconds(many, 2) - 1
    assert gain < MIN_MARGINAL_EFFICIENCY
    assert plan_ranks(many, 2).ranks == 1
    # paper-scale CG2 (45,000 particles of 2 mm, 7 slabs): 15 ranks (5 x 3) would be faster
    # but each added rank buys ~0.13 of a rank: it stays on its 7 slabs
    cg2 = CaseLoad("c", 45_000, 352_344, 0.06, 0.002, True, Bed(0.2, 0.17, 0.002))
    assert estimated_seconds(cg2, 15) < estimated_seconds(cg2, 7)
    assert (plan_ranks(cg2, None).ranks, plan_ranks(cg2, None).bound) == (7, "slab")


def test_the_runner_uses_the_planners_grid():
    wf = load_workflow(PAPER, ["sweep.cg_levels=[1]", "sweep.rules=[weber]",
                               "sweep.replicas=1", "sweep.per_cg={}"])
    (case,) = wf.cases
    scaled = case.scaled()
    load = case_load(case.case_id, scaled)
    plan = plan_ranks(load, None)
    across, axial = processor_grid(scaled, plan.ranks)
    assert (axial, across) == plan.grid == runner_grid(scaled, plan.ranks)
    g = case_grid(load, plan.ranks)
    assert (g.axial, g.across) == plan.grid


# ------------------------------------------------------------------ per-rank counts from a log

#: the production block of runs/demo/cg1-none-r0/log.liggghts (make demo, 2026-12-01; 1 rank)
LOG_1_RANK = """\
Loop time of 265.778 on 1 procs for 170227 steps with 2255 atoms, finish time Tue Dec  1 21:24:06 2026


Pair  time (%) = 199.994 (75.2483)
Neigh time (%) = 7.46695 (2.80947)
Comm  time (%) = 1.67965 (0.631975)
Outpt time (%) = 1.05794 (0.398053)
Other time (%) = 55.5802 (20.9122)

Nlocal:    2255 ave 2255 max 2255 min
Histogram: 1 0 0 0 0 0 0 0 0 0
Nghost:    469 ave 469 max 469 min
Histogram: 1 0 0 0 0 0 0 0 0 0
Neighs:    10387 ave 10387 max 10387 min
Histogram: 1 0 0 0 0 0 0 0 0 0
"""


def test_per_rank_atoms_and_ghosts_are_read_from_the_log():
    spread = last_run_spread("some header\n" + LOG_1_RANK)
    assert (spread.procs, spread.steps, spread.atoms) == (1, 170227, 2255)
    assert spread.local_avg * spread.procs == pytest.approx(spread.atoms)
    assert spread.imbalance == 1.0
    # one rank of a periodic slice keeps ghosts too (its own images across the boundary):
    # 469 / 2255 = 2 x 1.25 diameters / 18 mm, the halo depth the model uses
    assert spread.ghosts_per_local == pytest.approx(469 / 2255)
    assert spread.ghosts_per_local == pytest.approx(2 * 1.25 * 1.5 / 18, rel=0.01)
    assert spread.seconds["Comm"] == 1.67965
    # a block cut short (no Nlocal / Nghost yet) is not a block
    assert len(run_spreads(LOG_1_RANK + LOG_1_RANK.split("Nlocal")[0])) == 1
    with pytest.raises(ValueError, match="no complete 'Loop time' block"):
        last_run_spread("Loop time of 1 on 1 procs for 1 steps with 1 atoms\n")
