"""The rank planner: slab rule, particles per rank, cores, packing, overrides, bad input."""

from __future__ import annotations

import math

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from ligwf.engine.cores import available_cores
from ligwf.engine.decomposition import MIN_AXIAL_SLAB
from ligwf.engine.plan import (MIN_PARTICLES_PER_RANK, CaseLoad, allocation_schedule, case_load,
                               estimated_seconds, fixed_ranks, list_schedule_seconds,
                               override_schedule, particle_steps, plan_ranks, plan_study,
                               rank_limits)
from ligwf.errors import ConfigError
from ligwf.scene.workflow import load_workflow

from helpers import DRUM


def load(name="c", particles=1000, steps=10_000, length=0.009, d_max=0.001, wet=True):
    return CaseLoad(name, particles, steps, length, d_max, wet)


# --------------------------------------------------------------------- ranks of one case

def test_measured_cases_get_the_ranks_the_measurements_favour():
    # a few-hundred-particle CG3 slice (222 particles, 3 mm in a 9 mm slice): one rank
    assert plan_ranks(load(particles=222, d_max=0.003), cores=2).ranks == 1
    # CG1 of the 18 mm We-vs-Bo drum (11,963 particles) gained 1.49x from 2 axial ranks
    cg1 = plan_ranks(load(particles=11_963, length=0.018), cores=2)
    assert (cg1.ranks, cg1.bound) == (2, "cores")
    # the 9 mm CG1 (5,982 particles) did not clearly gain from 2: one rank
    assert plan_ranks(load(particles=5_982), cores=2).ranks == 1
    # paper scale CG1 (360,000 x 1 mm in 60 mm) on a cluster: the slab rule, 15 slabs
    paper = plan_ranks(load(particles=360_000, length=0.06), cores=None)
    assert (paper.ranks, paper.bound) == (15, "slab")


def test_slab_rule_counts_a_length_of_exactly_k_slabs_as_k():
    # 18 mm / (4 x 1.5 mm) is 3 slabs even where the division rounds to 2.9999...
    assert rank_limits(load(length=0.018, d_max=0.0015), None)["slab"] == 3
    assert rank_limits(load(length=0.012, d_max=0.003), None)["slab"] == 1


@settings(max_examples=300, deadline=None)
@given(particles=st.integers(1, 2_000_000), length=st.floats(1e-3, 1.0),
       d_max=st.floats(1e-5, 1e-2), cores=st.one_of(st.none(), st.integers(1, 512)))
def test_ranks_keep_the_slab_rule_the_cores_and_the_particles_per_rank(particles, length,
                                                                       d_max, cores):
    plan = plan_ranks(load(particles=particles, length=length, d_max=d_max), cores)
    assert plan.ranks >= 1
    if cores is not None:
        assert plan.ranks <= cores
    if plan.ranks > 1:
        # each slab along the axis is at least 4 largest diameters long ...
        assert length / plan.ranks >= MIN_AXIAL_SLAB * d_max * (1 - 1e-9)
        # ... and each rank carries at least the minimum number of particles
        assert particles / plan.ranks >= MIN_PARTICLES_PER_RANK
    assert plan.ranks == min(rank_limits(load(particles=particles, length=length,
                                              d_max=d_max), cores).values())


def test_case_load_and_particle_steps_from_a_scaled_scene():
    scaled = load_workflow(DRUM, []).cases[0].scaled()
    lo = case_load("cg1-none-r0", scaled)
    assert (lo.particles, lo.steps) == (scaled.particles.count, scaled.total_steps)
    assert (lo.drum_length, lo.d_max, lo.wet) == (scaled.drum.length, scaled.d_max, scaled.wet)
    assert lo.particle_steps == particle_steps(scaled) == scaled.particles.count * scaled.total_steps


def test_estimate_reproduces_the_measured_production_times():
    # 18 mm we_vs_bo production phases (bench_cg_speedup.py, docs/results/performance):
    # CG1 11,963 particles x 51,069 steps 334.8 s on 1 rank, 189.8 s on 2; CG2 1,495 x
    # 25,535 21.5 s; CG3 443 x 17,023 5.2 s
    cg1 = load(particles=11_963, steps=51_069, length=0.018)
    assert estimated_seconds(cg1, 1) == pytest.approx(334.8, rel=0.1)
    assert estimated_seconds(cg1, 2) == pytest.approx(189.8, rel=0.1)
    assert estimated_seconds(load(particles=1_495, steps=25_535), 1) == pytest.approx(21.5,
                                                                                      rel=0.1)
    assert estimated_seconds(load(particles=443, steps=17_023), 1) == pytest.approx(5.2, rel=0.1)
    assert estimated_seconds(load(wet=False), 1) < estimated_seconds(load(wet=True), 1)


# ------------------------------------------------------------------------ the schedule

def test_single_rank_cases_run_side_by_side_longest_first_and_fill_the_cores():
    loads = [load("short", steps=1_000), load("long", steps=50_000),
             load("mid", steps=10_000), load("mid2", steps=10_000)]
    sched = plan_study(loads, cores=2)
    assert [c.name for c in sched.cases] == ["short", "long", "mid", "mid2"]   # study order
    (phase,) = sched.phases
    assert (phase.ranks, phase.groups, phase.ensemble) == (1, 2, True)
    assert phase.total_ranks == sched.cores
    assert phase.cases == ("long", "mid", "mid2", "short")    # ties keep study order


def test_bigger_cases_run_first_on_several_ranks_then_the_small_ones_side_by_side():
    loads = [load("cg3", particles=400), load("cg1", particles=12_000, length=0.018),
             load("cg2", particles=1_500)]
    sched = plan_study(loads, cores=2)
    assert [(p.ranks, p.groups, p.ensemble, p.cases) for p in sched.phases] == [
        (2, 1, False, ("cg1",)), (1, 2, True, ("cg2", "cg3"))]
    assert sched.ranks_of("cg1") == 2 and sched.ranks_of("cg3") == 1


def test_a_lone_case_runs_under_mpirun_not_as_an_ensemble():
    (phase,) = plan_study([load()], cores=8).phases
    assert (phase.groups, phase.ensemble) == (1, False)
    assert plan_study([], cores=2).phases == ()


def test_ensembles_of_multi_rank_groups_when_the_cores_hold_several():
    loads = [load(f"c{i}", particles=6_500, length=0.018) for i in range(3)]   # 2 ranks each
    (phase,) = plan_study(loads, cores=4).phases
    assert (phase.ranks, phase.groups, phase.total_ranks, phase.ensemble) == (2, 2, 4, True)


@settings(max_examples=200, deadline=None)
@given(sizes=st.lists(st.integers(50, 50_000), min_size=1, max_size=12),
       cores=st.integers(1, 16))
def test_every_case_is_scheduled_once_and_no_phase_asks_for_more_than_the_cores(sizes, cores):
    loads = [load(f"c{i}", particles=n, steps=1000 + 37 * i, length=0.05)
             for i, n in enumerate(sizes)]
    sched = plan_study(loads, cores)
    scheduled = [name for p in sched.phases for name in p.cases]
    assert sorted(scheduled) == sorted(c.name for c in loads)
    ranks = [p.ranks for p in sched.phases]
    assert ranks == sorted(set(ranks), reverse=True)          # widest phase first
    for p in sched.phases:
        assert p.total_ranks <= cores
        # the phase fills the cores unless it has fewer cases than would fit
        assert p.groups == min(cores // p.ranks, len(p.cases))
        times = [estimated_seconds(next(l for l in loads if l.name == n), p.ranks)
                 for n in p.cases]
        assert times == sorted(times, reverse=True)            # longest first
    assert 0.0 < sched.core_fill <= 1.0


def test_list_schedule_matches_hand_worked_answers():
    assert list_schedule_seconds([3, 2, 2, 1], 2) == 4
    assert list_schedule_seconds([5, 1, 1, 1], 2) == 5
    assert list_schedule_seconds([1, 1, 1], 1) == 3


# ------------------------------------------------------------- one allocation per case

def test_allocation_schedule_gives_each_case_the_plan_ranks_one_phase_per_rank_count():
    loads = [load("small", particles=100), load("big", particles=12_000, length=0.018),
             load("big2", particles=12_000, length=0.018), load("tiny", particles=50)]
    sched = allocation_schedule(loads, cores_per_case=None)
    assert [(c.name, c.ranks) for c in sched.cases] == [
        (l.name, plan_ranks(l, None).ranks) for l in loads]
    assert sched.planned and sched.cores == sum(c.ranks for c in sched.cases)
    # widest first, study order inside a phase, every case its own allocation (no ensemble)
    assert [(ph.ranks, ph.groups, ph.cases, ph.ensemble) for ph in sched.phases] == [
        (4, 2, ("big", "big2"), False), (1, 2, ("small", "tiny"), False)]
    capped = allocation_schedule(loads, cores_per_case=2)
    assert [(c.ranks, c.bound) for c in capped.cases][1] == (2, "cores")
    fixed = allocation_schedule(loads, fixed=(3, "--ntasks"))
    assert not fixed.planned and {(c.ranks, c.bound) for c in fixed.cases} == {(3, "--ntasks")}
    assert [(ph.ranks, ph.cases) for ph in fixed.phases] == [(3, ("small", "big", "big2",
                                                                   "tiny"))]
    with pytest.raises(ConfigError, match="each case must appear once"):
        allocation_schedule([load("a"), load("a")])


# ---------------------------------------------------------------------------- overrides

def test_np_override_puts_every_case_on_np_ranks_one_after_the_other_in_study_order():
    loads = [load("small", particles=100), load("big", particles=12_000, length=0.018)]
    sched = override_schedule(loads, nprocs=3, cores=2)    # more than the cores: as asked
    assert [c.ranks for c in sched.cases] == [3, 3] and not sched.planned
    (phase,) = sched.phases
    assert (phase.ranks, phase.groups, phase.ensemble, phase.cases) == (3, 1, False,
                                                                        ("small", "big"))


def test_ensemble_override_runs_all_cases_in_one_ensemble_in_study_order():
    loads = [load("a", steps=10), load("b", steps=10_000), load("c", steps=100)]
    (phase,) = override_schedule(loads, nprocs=1, ensemble=2).phases
    assert (phase.ranks, phase.groups, phase.ensemble, phase.cases) == (1, 2, True,
                                                                        ("a", "b", "c"))
    assert [c.bound for c in fixed_ranks(loads, 4, "--ntasks")] == ["--ntasks"] * 3


# ---------------------------------------------------------------------------- bad input

@pytest.mark.parametrize("kwargs, field, allowed", [
    ({"particles": 0}, "particles = 0", "[1, inf)"),
    ({"steps": -5}, "steps = -5", "[1, inf)"),
    ({"d_max": 0.0}, "d_max = 0.0", "(0, inf)"),
    ({"length": -0.01}, "drum_length = -0.01", "(0, inf)"),
    ({"length": math.nan}, "drum_length = nan", "(0, inf)"),
])
def test_bad_case_values_are_refused_with_field_and_range(kwargs, field, allowed):
    with pytest.raises(ConfigError) as err:
        load(**kwargs)
    assert field in str(err.value) and allowed in str(err.value) and "'c'" in str(err.value)


@pytest.mark.parametrize("call, field", [
    (lambda: plan_study([load()], cores=0), "cores = 0"),
    (lambda: plan_ranks(load(), cores=-1), "cores = -1"),
    (lambda: plan_ranks(load(), cores=2, min_particles_per_rank=0), "min_particles_per_rank = 0"),
    (lambda: override_schedule([load()], nprocs=0), "--np = 0"),
    (lambda: override_schedule([load()], nprocs=1, ensemble=-2), "--ensemble = -2"),
    (lambda: estimated_seconds(load(), 0), "ranks = 0"),
])
def test_bad_counts_are_refused_with_field_and_range(call, field):
    with pytest.raises(ConfigError) as err:
        call()
    assert field in str(err.value) and "allowed range [" in str(err.value)


def test_ensemble_must_split_into_groups_of_np():
    with pytest.raises(ConfigError, match=r"--ensemble = 3: must be a multiple of --np = 2 "
                                          r"\(allowed: 2, 4, 6, \.\.\.\)"):
        override_schedule([load()], nprocs=2, ensemble=3)


def test_a_case_named_twice_is_refused():
    with pytest.raises(ConfigError, match="case names = \\['a'\\]"):
        plan_study([load("a"), load("a")], cores=2)


# ------------------------------------------------------------------------------- cores

def test_cores_come_from_the_option_then_the_slurm_allocation_then_the_affinity():
    slurm = {"SLURM_JOB_ID": "7", "SLURM_NTASKS": "16"}
    assert available_cores(3, slurm, 2) == (3, "--cores")
    assert available_cores(None, slurm, 2) == (16, "SLURM_NTASKS")
    assert available_cores(None, {"SLURM_NTASKS": "16"}, 2)[0] == 2     # not in a job
    assert available_cores(None, {}, 2) == (2, "CPUs this process may use")


@pytest.mark.parametrize("explicit, env, field", [
    (0, {}, "--cores = 0"),
    (None, {"SLURM_JOB_ID": "7", "SLURM_NTASKS": "two"}, "SLURM_NTASKS = 'two'"),
    (None, {"SLURM_JOB_ID": "7", "SLURM_NTASKS": "0"}, "SLURM_NTASKS = '0'"),
])
def test_bad_core_counts_are_refused(explicit, env, field):
    with pytest.raises(ConfigError) as err:
        available_cores(explicit, env, 2)
    assert field in str(err.value) and "allowed range [1, inf)" in str(err.value)
