"""What a Slurm submission asks of the cluster, case by case: ranks, nodes and wall time.

Pure functions over the rank plan (:mod:`ligwf.engine.plan`). Nodes per case come from the
cores of one node (``--cores-per-node`` or the site's ``slurm: cores_per_node``) at one
rank per core; unknown cores per node leave the nodes to Slurm. The estimated wall time
of a case (:func:`ligwf.engine.plan.estimated_seconds`, rates measured on one 2-core
machine) is set against the ``--time`` its array task asks for, so a case Slurm would stop
at the limit is seen before it is submitted. :func:`plan_rows` gives the rows of the table
``ligwf slurm submit`` prints; replicas with the same load share one row.
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from typing import Hashable, Sequence

from ligwf.engine.decomposition import (GHOST_COST, HALO_DIAMETERS, MIN_AXIAL_SLAB,
                                        PLANNING_SURFACE_DEG)
from ligwf.engine.plan import (BOUND_PARTICLES, BOUND_SLAB, MIN_GRID_EFFICIENCY,
                               MIN_MARGINAL_EFFICIENCY, MULTI_RANK_EFFICIENCY, WET_RATE, CaseLoad, RankPlan, case_grid,
                               rank_limits)
from ligwf.errors import ConfigError
from ligwf.slurm.site import slurm_time_problem



def nodes_for(ranks: int, cores_per_node: int | None) -> int | None:
    """Nodes that ``ranks`` MPI ranks fill at one rank per core: ceil(ranks /
    cores_per_node); None when the cores per node are unknown."""
    if isinstance(ranks, bool) or not isinstance(ranks, int) or ranks < 1:
        raise ConfigError(f"ranks = {ranks!r}: must be a whole number (allowed range [1, inf))")
    if cores_per_node is None:
        return None
    if (isinstance(cores_per_node, bool) or not isinstance(cores_per_node, int)
            or cores_per_node < 1):
        raise ConfigError(f"cores per node = {cores_per_node!r}: must be a whole number "
                          "(allowed range [1, inf))")
    return -(-ranks // cores_per_node)


def slurm_time_seconds(text: str | None) -> int | None:
    """Seconds of a Slurm ``--time`` value; None when unset or 0 (Slurm: no limit).

    Slurm reads a lone number as minutes, ``A:B`` as minutes:seconds and ``A:B:C`` as
    hours:minutes:seconds, but after a day count ``D-A:B`` is hours:minutes.

    >>> slurm_time_seconds("02:00:00"), slurm_time_seconds("90"), slurm_time_seconds("1-12")
    (7200, 5400, 129600)
    """
    if text is None:
        return None
    text = text.strip()
    why = slurm_time_problem(text)          # the forms and ranges the site settings accept
    if why is not None:
        raise ConfigError(f"time = {text!r}: {why}")
    days, _, clock = text.rpartition("-")
    parts = [int(p) for p in clock.split(":")]
    if days:                                                # D-H, D-H:M, D-H:M:S
        parts += [0] * (3 - len(parts))
        seconds = int(days) * 86400 + parts[0] * 3600 + parts[1] * 60 + parts[2]
    elif len(parts) == 1:                                   # M
        seconds = parts[0] * 60
    elif len(parts) == 2:                                   # M:S
        seconds = parts[0] * 60 + parts[1]
    else:                                                   # H:M:S
        seconds = parts[0] * 3600 + parts[1] * 60 + parts[2]
    return seconds or None


def hours_minutes(seconds: float) -> str:
    """A wall time as h:mm, rounded up to the next minute (a budget, not a record):
    24,480 s -> '6:48', 61 s -> '0:02', 100 h -> '100:00'."""
    if not seconds >= 0 or seconds == float("inf"):
        raise ConfigError(f"wall time = {seconds!r} s: allowed range [0, inf)")
    minutes = math.ceil(seconds / 60)
    return f"{minutes // 60}:{minutes % 60:02d}"


@dataclass(frozen=True)
class PlanRow:
    """One row of the Slurm plan: a case, or replicas with the same load and ranks."""

    cases: tuple[str, ...]      # case names, study order
    load: CaseLoad              # the first case's (every case of a row has the same load)
    ranks: int
    bound: str                  # what limited the ranks (RankPlan.bound)
    nodes: int | None           # None: cores per node unknown
    estimated_seconds: float    # wall seconds of ONE of the cases (each is its own task)
    efficiency: float = 1.0     # modelled share of the ideal speed-up (RankPlan.efficiency)

    @property
    def label(self) -> str:
        """The first case's name, '+N more' when the row stands for N more cases."""
        more = len(self.cases) - 1
        return self.cases[0] + (f" +{more} more" if more else "")

    @property
    def slab_bound(self) -> bool:
        """The axial slab rule alone limited the ranks (particles would allow more)."""
        return self.bound == BOUND_SLAB

    def exceeds(self, time_limit_seconds: int | None) -> bool:
        """Whether the estimate is longer than the array task's time limit (None: no limit
        asked for, nothing to compare)."""
        return time_limit_seconds is not None and self.estimated_seconds > time_limit_seconds


def plan_rows(loads: Sequence[CaseLoad], plans: Sequence[RankPlan],
              groups: Sequence[Hashable], cores_per_node: int | None) -> tuple[PlanRow, ...]:
    """The plan table's rows: ``loads[i]`` planned as ``plans[i]``; cases with the same
    ``groups[i]`` (e.g. CG level and rule, so replicas) AND the same load and ranks share
    a row, in order of first appearance."""
    if not len(loads) == len(plans) == len(groups):
        raise ConfigError(f"plan rows: {len(loads)} loads, {len(plans)} plans and "
                          f"{len(groups)} groups must be as many")
    rows: dict[tuple, tuple[CaseLoad, RankPlan, list[str]]] = {}
    for load, plan, group in zip(loads, plans, groups):
        if plan.name != load.name:
            raise ConfigError(f"plan rows: plan {plan.name!r} is not case {load.name!r}")
        key = (group, load.particles, load.steps, load.wet, load.drum_length, load.d_max,
               plan.ranks, plan.bound)
        rows.setdefault(key, (load, plan, []))[2].append(load.name)
    return tuple(PlanRow(tuple(names), load, plan.ranks, plan.bound,
                         nodes_for(plan.ranks, cores_per_node), plan.estimated_seconds,
                         plan.efficiency)
                 for load, plan, names in rows.values())


def slab_note(row: PlanRow) -> str:
    """Why a row's ranks stop at the axial slab rule, in numbers."""
    load = row.load
    by_particles = rank_limits(load, None)[BOUND_PARTICLES]
    return (f"{row.label}: {row.ranks} ranks is the axial slab limit, "
            f"{load.drum_length * 1e3:g} mm / ({MIN_AXIAL_SLAB:g} x {load.d_max * 1e3:g} mm "
            f"largest diameter); particles alone would allow {by_particles} (slabs along "
            "the axis only)")


def grid_note(row: PlanRow) -> str | None:
    """The grid of a multi-rank row and what its estimated wall time and efficiency rest
    on, in numbers (None for a one-rank row or a grid the model cannot cost)."""
    if row.ranks == 1:
        return None
    load = row.load
    try:
        grid = case_grid(load, row.ranks)
    except ConfigError:
        return None
    slab = load.drum_length / grid.axial * 1e3
    text = (f"{row.label}: {row.ranks} ranks = {grid.axial} slab(s) along the axis "
            f"({slab:.3g} mm, >= {MIN_AXIAL_SLAB:g} x {load.d_max * 1e3:g} mm)")
    if grid.across > 1 and load.bed is not None:
        width = load.bed.box_width / grid.across * 1e3
        text += (f" x {grid.across} columns across ({width:.3g} mm); efficiency "
                 f"{row.efficiency:.2f} = uniform columns (LIGGGHTS 3.8.0 has no load "
                 f"balancing) over a bed filling {load.bed.fill_fraction:g} of the drum with "
                 f"its surface at {PLANNING_SURFACE_DEG:g} deg: largest rank "
                 f"{grid.imbalance:.2f}x the average")
    else:
        text += f"; efficiency {row.efficiency:.2f}"
    text += (f"; halo {grid.ghost_ratio:.2f} ghosts per particle ({HALO_DIAMETERS:g} "
             f"diameters deep, 1 rank: {grid.ghost_ratio_one:.2f}) at {GHOST_COST:g} of a "
             f"particle's cost (fit to {MULTI_RANK_EFFICIENCY:g} measured on 2 axial ranks); "
             f"grids below {MIN_GRID_EFFICIENCY:g}, or whose added ranks add less than "
             f"{MIN_MARGINAL_EFFICIENCY:g} of a rank's speed each, are not used")
    return text


def estimate_basis(rows: Sequence[PlanRow]) -> list[str]:
    """What every estimate of ``rows`` rests on: per multi-rank row its grid and efficiency
    (:func:`grid_note`), then the rates and where the model is written down."""
    notes = [n for n in (grid_note(r) for r in rows) if n]
    if notes:
        notes.append(f"estimates: {WET_RATE:.2g} wet particle-steps per core-second measured "
                     "on a 2-core machine (ligwf.engine.plan) / efficiency; the efficiency "
                     "beyond 2 ranks is the model of docs/results/performance/"
                     "scaling_model.md, not a measurement: measure it with "
                     "benchmarks/bench_scaling_slurm.py")
    return notes


def over_time_warning(row: PlanRow, time: str) -> str:
    """The warning for a row whose estimate exceeds ``--time`` (one line, no traceback)."""
    cases = f" (each of {len(row.cases)} cases)" if len(row.cases) > 1 else ""
    return (f"{row.label}: estimated {hours_minutes(row.estimated_seconds)} (h:mm) on "
            f"{row.ranks} rank(s){cases} exceeds --time {time}; Slurm stops the task at the "
            "limit (the runner then saves a restart and 'ligwf slurm resubmit' continues "
            "it): ask for a longer --time")
