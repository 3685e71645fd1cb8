"""Rank planning: how many MPI ranks each case gets, and how a study's cases share the cores.

Pure functions over frozen dataclasses; the one reader of the environment is
:func:`machine_cores` (:mod:`ligwf.engine.cores`). Three rules decide, each from a measurement on the
project's 2-core machine (``docs/results/README.md``, issue 15):

* **Slabs along the drum axis first, then columns across.** A case is cut into slabs along
  its axis, never along gravity (a settled bed lies in the lower half: 96 % of it on one of
  2 ranks); each slab is at least ``MIN_AXIAL_SLAB`` (4) of the case's LARGEST diameters
  long (:func:`ligwf.engine.decomposition.axial_slab_limit`): a 9 mm slice of 3 mm CG3
  particles runs on one rank. A case that could use more ranks than slabs is also cut
  across the drum (:mod:`ligwf.engine.decomposition`: 3.8.0 cannot balance the load, a
  turning bed fills uniform columns unevenly) while the modelled efficiency stays >=
  ``MIN_GRID_EFFICIENCY``, every added rank buys ``MIN_MARGINAL_EFFICIENCY`` of a rank's
  speed and the run gets shorter; the runner uses the same grid.
* **Enough particles per rank.** Each step of a case costs a fixed ~0.08 ms (turning mesh,
  fixes) besides its pair work, and every extra rank adds exchanges; a rank should carry
  thousands of particles, or splitting buys little and costs core-seconds. Measured
  (``benchmarks/bench_cg_speedup.py``, docs/results/performance): the 18 mm CG1 case (11,963
  particles, ~6,000 a rank) ran its production 1.76x faster on 2 axial ranks than on one
  (0.88 of the ideal); a 708-particle CG2 case on 2 ranks spent half its loop exchanging.
  Hence ``MIN_PARTICLES_PER_RANK``.
* **Cores stay filled, longest first.** Cases with the same rank count form one phase:
  single-rank cases run side by side as members of one MPI ensemble
  (:mod:`ligwf.engine.ensemble`; separate ``mpirun -np 1`` would all bind to core 0),
  a phase of one group runs its cases one after the other under ``mpirun``. Phases run
  widest first, and inside a phase the longest case is claimed first (list scheduling:
  the short ones fill the gaps at the end).

The cost of a case is its particle-steps (particles x steps, what ``ligwf check`` prints);
wall-time estimates use the rates below and are only as good as those measurements.
``--np`` / ``--ensemble`` bypass the planner: :func:`override_schedule` describes what
they do (today's meaning) so ``check`` and ``run`` can show it the same way.

On a batch scheduler every case runs in an allocation of its own (an array task):
:func:`allocation_schedule` gives each case its ranks by the same :func:`plan_ranks` (the
cores per case, if capped, instead of the machine's) and one phase per rank count, each
phase one array of side-by-side allocations.
"""

from __future__ import annotations

import heapq
import math
from dataclasses import dataclass
from typing import Mapping, Sequence

from ligwf.engine.decomposition import (Bed, GridCost, axial_slab_limit, best_grid,
                                        scene_bed)
from ligwf.engine.cores import at_least
from ligwf.errors import ConfigError
from ligwf.scene.scaled import ScaledScene

#: Fewest particles a rank should carry (see the module docstring): 11,963 particles gain
#: 1.76x from 2 ranks; a few hundred lose.
MIN_PARTICLES_PER_RANK = 3000
#: Fixed wall seconds per step of one wet case on one rank, whatever its size, and the
#: marginal particle-steps per core-second: a line through the production phases of the
#: 18 mm we_vs_bo cases on one rank, one case at a time on the idle machine
#: (bench_cg_speedup.py, 2026-11-28): 443 particles 0.306 ms/step, 1,495 0.842 ms,
#: 11,963 6.56 ms. The line is within 8 % of all three.
STEP_OVERHEAD_SECONDS = 0.08e-3
WET_RATE = 1.8e6
#: Dry contacts run this much faster per particle-step (2.5-3.3 vs 1.5-1.7 M by hand,
#: an older measurement).
DRY_SPEEDUP = 1.8
#: Share of the ideal speed-up a case keeps on more than one rank (11,963 particles:
#: 379.5 production core-s on 2 axial ranks against 334.8 on one). Measured at 2 ranks
#: only; other grids take theirs from the decomposition model calibrated on it
#: (:func:`ligwf.engine.decomposition.grid_cost`, scaling_model.md).
MULTI_RANK_EFFICIENCY = 0.88
#: Lowest modelled efficiency of a grid cut across the drum the planner accepts: more
#: ranks at less than a quarter of their ideal speed cost 4x the core-hours for their gain
MIN_GRID_EFFICIENCY = 0.25
#: ... and each rank it adds beyond the slabs must add at least this share of one rank's
#: ideal speed: a case whose columns buy little stays on its slabs (paper-scale CG2: 15
#: ranks instead of 7 slabs would be 18 % faster for 76 % more core-hours; CG1's 119 add
#: 0.23 each)
MIN_MARGINAL_EFFICIENCY = 0.2

#: What limited a case's ranks (:attr:`RankPlan.bound`).
BOUND_PARTICLES, BOUND_SLAB, BOUND_CORES = "particles", "slab", "cores"
#: a grid across the drum set the ranks (fastest one within MIN_GRID_EFFICIENCY)
BOUND_GRID = "grid"
BOUND_NP, BOUND_ENSEMBLE = "--np", "--ensemble"
#: most MPI ranks ligwf launches for one case or ensemble (2**20, beyond the largest
#: machines' jobs): an absurd --np would otherwise spin in the processor-grid search
MAX_RANKS = 2**20


@dataclass(frozen=True)
class CaseLoad:
    """What the planner needs to know about one case (taken from its scaled scene)."""

    name: str
    particles: int          # scaled particle count
    steps: int              # fill + settle + production
    drum_length: float      # m, along the axis (the periodic slice)
    d_max: float            # m, the largest scaled diameter
    wet: bool = True
    #: the cross-section (drum diameter, fill): None keeps the case to axial slabs
    bed: Bed | None = None
    periodic: bool = True

    def __post_init__(self) -> None:
        where = f"case {self.name!r}: " if self.name else ""
        if not self.name:
            raise ConfigError("case name = '': must not be empty")
        at_least(f"{where}particles", self.particles, 1)
        at_least(f"{where}steps", self.steps, 1)
        for field in ("drum_length", "d_max"):
            value = getattr(self, field)
            if not isinstance(value, (int, float)) or not value > 0 or value == float("inf"):
                raise ConfigError(f"{where}{field} = {value!r}: allowed range (0, inf) m")

    @property
    def particle_steps(self) -> int:
        """The case's cost in particle-steps (what ``ligwf check`` prints)."""
        return self.particles * self.steps


def particle_steps(scaled: ScaledScene) -> int:
    """Particles x total steps of a scaled case: the cost the planner packs by."""
    return scaled.particles.count * scaled.total_steps


def case_load(name: str, scaled: ScaledScene) -> CaseLoad:
    """The planner's view of a scaled case."""
    return CaseLoad(name, scaled.particles.count, scaled.total_steps, scaled.drum.length,
                    scaled.d_max, scaled.wet, scene_bed(scaled), scaled.drum.periodic)


def case_grid(load: CaseLoad, ranks: int) -> GridCost:
    """The processor grid ``load`` runs on at ``ranks`` ranks and its modelled cost (the
    runner's grid: :func:`ligwf.engine.render.processor_grid`)."""
    return best_grid(at_least("ranks", ranks, 1), load.drum_length, load.d_max,
                     load.periodic, load.bed)


def efficiency(load: CaseLoad, ranks: int) -> float:
    """Share of the ideal speed-up ``load`` keeps on ``ranks`` ranks: 1 on one rank, else
    the decomposition model's for the case's grid (calibrated on the one measurement, 0.88
    on 2 axial ranks); :data:`MULTI_RANK_EFFICIENCY` where no grid fits or its cost is
    unknown (a cut across a drum whose bed is not given, e.g. ``--np`` beyond the slabs)."""
    if at_least("ranks", ranks, 1) == 1:
        return 1.0
    try:
        value = case_grid(load, ranks).efficiency
    except ConfigError:
        return MULTI_RANK_EFFICIENCY
    return value if math.isfinite(value) else MULTI_RANK_EFFICIENCY


def estimated_seconds(load: CaseLoad, ranks: int) -> float:
    """Wall seconds of ``load`` on ``ranks`` ranks from the measured rates and
    :func:`efficiency` (an estimate: the fill phase has fewer particles, and the rates are
    one machine's)."""
    rate = WET_RATE * (1.0 if load.wet else DRY_SPEEDUP)
    return load.steps * (STEP_OVERHEAD_SECONDS
                         + load.particles / (ranks * rate * efficiency(load, ranks)))


@dataclass(frozen=True)
class RankPlan:
    """Ranks of one case, what limited them, and its estimated wall time."""

    name: str
    ranks: int
    bound: str                  # BOUND_* names that set ``ranks`` ("slab, particles")
    particle_steps: int
    estimated_seconds: float
    efficiency: float = 1.0     # share of the ideal speed-up (:func:`efficiency`)
    grid: tuple[int, int] = (1, 1)   # ranks (along the axis, across); (0, 0): none fits


def case_plan(load: CaseLoad, ranks: int, bound: str) -> RankPlan:
    """The :class:`RankPlan` of ``load`` on ``ranks`` ranks (its grid, efficiency, time)."""
    try:
        grid = case_grid(load, ranks)
        axes = (grid.axial, grid.across)
    except ConfigError:             # --np no grid fits: the runner cuts it as it can
        axes = (0, 0)
    return RankPlan(load.name, ranks, bound, load.particle_steps,
                    estimated_seconds(load, ranks), efficiency(load, ranks), axes)


def rank_limits(load: CaseLoad, cores: int | None,
                min_particles_per_rank: int = MIN_PARTICLES_PER_RANK) -> dict[str, int]:
    """Each rule's largest rank count for ``load``: particles per rank, the axial slab
    rule and (when given) the cores."""
    at_least("min_particles_per_rank", min_particles_per_rank, 1)
    limits = {BOUND_SLAB: axial_slab_limit(load.drum_length, load.d_max),
              BOUND_PARTICLES: max(1, load.particles // min_particles_per_rank)}
    if cores is not None:
        limits[BOUND_CORES] = at_least("cores", cores, 1)
    return limits


def plan_ranks(load: CaseLoad, cores: int | None,
               min_particles_per_rank: int = MIN_PARTICLES_PER_RANK) -> RankPlan:
    """Ranks for one case: the smallest of :func:`rank_limits` (``cores`` None: no core
    limit, as for a Slurm array task that gets its own allocation); beyond the slabs, when
    the particles and cores allow more, the fastest grid across the drum
    (:func:`across_ranks`)."""
    limits = rank_limits(load, cores, min_particles_per_rank)
    ranks = min(limits.values())
    bound = ", ".join(name for name, value in limits.items() if value == ranks)
    others = [v for k, v in limits.items() if k != BOUND_SLAB]
    if load.bed is not None and ranks == limits[BOUND_SLAB] and min(others) > ranks:
        wider = across_ranks(load, min(others))
        if wider > ranks:
            ranks = wider
            bound = ", ".join([BOUND_GRID] + [k for k, v in limits.items()
                                               if k != BOUND_SLAB and v == ranks])
    return case_plan(load, ranks, bound)


def across_ranks(load: CaseLoad, most: int) -> int:
    """The rank count up to ``most`` with the shortest estimated wall time among grids that
    fit (slabs and columns of >= MIN_AXIAL_SLAB diameters), keep at least
    MIN_GRID_EFFICIENCY, and whose ranks beyond the slabs each add at least
    MIN_MARGINAL_EFFICIENCY of a rank's ideal speed; ties go to fewer ranks. At least the
    slab limit."""
    slabs = best = axial_slab_limit(load.drum_length, load.d_max)
    one = estimated_seconds(load, 1)
    best_time = slab_time = estimated_seconds(load, slabs)
    for ranks in range(best + 1, most + 1):
        try:
            grid = case_grid(load, ranks)
        except ConfigError:         # no grid of this many ranks fits the case
            continue
        if grid.efficiency < MIN_GRID_EFFICIENCY:
            continue
        seconds = estimated_seconds(load, ranks)
        if (one / seconds - one / slab_time) / (ranks - slabs) < MIN_MARGINAL_EFFICIENCY:
            continue
        seconds = estimated_seconds(load, ranks)
        if seconds < best_time * (1 - 1e-9):
            best, best_time = ranks, seconds
    return best


@dataclass(frozen=True)
class Phase:
    """Cases that run in one go on ``groups`` rank groups of ``ranks`` each.

    ``ensemble``: all in ONE ``mpirun`` of ``groups x ranks`` ranks, each group claiming
    the next case of ``cases`` (:func:`ligwf.engine.ensemble.run_ensemble`); otherwise one
    case after the other under ``mpirun -np ranks`` (on a batch scheduler,
    :func:`allocation_schedule`: every case its own group in an allocation of its own).
    """

    ranks: int
    groups: int
    cases: tuple[str, ...]      # in claim order (planned: longest first)
    ensemble: bool
    estimated_seconds: float    # until the last group is done

    @property
    def total_ranks(self) -> int:
        return self.ranks * self.groups


@dataclass(frozen=True)
class Schedule:
    """How a study's cases run on ``cores`` cores: per case ranks, then phases in order."""

    cores: int
    cases: tuple[RankPlan, ...]     # in study order
    phases: tuple[Phase, ...]       # in run order
    planned: bool                   # False: what --np / --ensemble ask for

    def ranks_of(self, name: str) -> int:
        """The ranks of case ``name`` (KeyError if it is not in the schedule)."""
        return {c.name: c.ranks for c in self.cases}[name]

    @property
    def estimated_seconds(self) -> float:
        """Estimated wall time of the whole schedule (phases run one after the other)."""
        return sum(p.estimated_seconds for p in self.phases)

    @property
    def core_fill(self) -> float:
        """Estimated busy core-seconds / (cores x estimated wall time), in [0, 1]."""
        wall = self.estimated_seconds
        busy = sum(c.ranks * c.estimated_seconds for c in self.cases)
        return min(1.0, busy / (self.cores * wall)) if wall > 0 else 0.0


def list_schedule_seconds(durations: Sequence[float], groups: int) -> float:
    """When the last of ``durations`` ends if ``groups`` workers each take the next one
    in order as soon as they are free (what the ensemble's claims do)."""
    at_least("groups", groups, 1)
    free = [0.0] * groups
    for d in durations:
        heapq.heappush(free, heapq.heappop(free) + d)
    return max(free)


def _unique_names(loads: Sequence[CaseLoad]) -> None:
    names = [l.name for l in loads]
    if len(set(names)) != len(names):
        dup = sorted({n for n in names if names.count(n) > 1})
        raise ConfigError(f"case names = {dup}: each case must appear once in a schedule")


def plan_study(loads: Sequence[CaseLoad], cores: int,
               min_particles_per_rank: int = MIN_PARTICLES_PER_RANK) -> Schedule:
    """Ranks per case and the phases that pack them onto ``cores`` cores (see the module
    docstring): one phase per rank count, widest first; in a phase as many groups as
    fit the cores (never more than its cases), longest case first."""
    at_least("cores", cores, 1)
    _unique_names(loads)
    plans = tuple(plan_ranks(l, cores, min_particles_per_rank) for l in loads)
    phases = []
    for ranks in sorted({p.ranks for p in plans}, reverse=True):
        members = sorted((p for p in plans if p.ranks == ranks),
                         key=lambda p: -p.estimated_seconds)   # stable: ties keep study order
        groups = min(cores // ranks, len(members))
        phases.append(Phase(ranks, groups, tuple(p.name for p in members), groups > 1,
                            list_schedule_seconds([p.estimated_seconds for p in members],
                                                  groups)))
    return Schedule(cores, plans, tuple(phases), planned=True)


def allocation_schedule(loads: Sequence[CaseLoad], cores_per_case: int | None = None,
                        fixed: tuple[int, str] | None = None) -> Schedule:
    """How a batch scheduler runs the cases, each in an allocation of its own: ranks per
    case from :func:`plan_ranks` with at most ``cores_per_case`` (None: no core limit
    beyond the slab and particle rules), or every case on ``fixed = (ranks, option)``
    ranks because that option says so. One phase per rank count, widest first, its cases
    in study order, each its own group (the scheduler runs them side by side as the
    cluster allows; ``ensemble`` False). ``cores``: the ranks of all cases at once."""
    _unique_names(loads)
    plans = (fixed_ranks(loads, *fixed) if fixed is not None
             else tuple(plan_ranks(l, cores_per_case) for l in loads))
    phases = []
    for ranks in sorted({p.ranks for p in plans}, reverse=True):
        members = tuple(p for p in plans if p.ranks == ranks)
        phases.append(Phase(ranks, len(members), tuple(p.name for p in members), False,
                            max(p.estimated_seconds for p in members)))
    return Schedule(max(1, sum(p.ranks for p in plans)), plans, tuple(phases),
                    planned=fixed is None)


def fixed_ranks(loads: Sequence[CaseLoad], ranks: int, bound: str) -> tuple[RankPlan, ...]:
    """Every case on ``ranks`` ranks because option ``bound`` says so (no planning)."""
    at_least(bound, ranks, 1)
    return tuple(case_plan(l, ranks, bound) for l in loads)


def override_schedule(loads: Sequence[CaseLoad], nprocs: int, ensemble: int = 0,
                      cores: int | None = None) -> Schedule:
    """What ``--np K`` (every case on K ranks, one after the other) or ``--ensemble P``
    (all cases, in study order, in one mpirun of P ranks, groups of K) do: no planning,
    no core limit (the user asked for it); ``cores`` only for the fill estimate."""
    at_least("--np", nprocs, 1)
    at_least("--ensemble", ensemble, 0)
    for field, value in (("--np", nprocs), ("--ensemble", ensemble)):
        if value > MAX_RANKS:
            raise ConfigError(f"{field} = {value}: allowed range [1, {MAX_RANKS}] MPI ranks")
    if ensemble and ensemble % nprocs:
        raise ConfigError(f"--ensemble = {ensemble}: must be a multiple of --np = {nprocs} "
                          f"(allowed: {nprocs}, {2 * nprocs}, {3 * nprocs}, ...)")
    _unique_names(loads)
    plans = fixed_ranks(loads, nprocs, BOUND_ENSEMBLE if ensemble else BOUND_NP)
    groups = ensemble // nprocs if ensemble else 1
    phases = ((Phase(nprocs, groups, tuple(p.name for p in plans), bool(ensemble),
                     list_schedule_seconds([p.estimated_seconds for p in plans], groups)),)
              if plans else ())
    used = cores if cores is not None else (ensemble or nprocs)
    return Schedule(at_least("cores", used, 1), plans, phases, planned=False)
