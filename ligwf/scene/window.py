"""Whether the production run leaves the held-granule analysis any frames, said before it runs.

``analysis.granules: held`` counts a bridge only when it is present in every frame of
``[t, t + hold_time]``, and the granule controls then follow each granule a quarter of a
revolution further (pair persistence at T/4). Both come out of the steady window, which starts
after the start-up the analysis leaves out: ``steady_after`` as a fraction, or with ``auto`` up
to :data:`AUTO_LATEST` of production (``ligwf.analysis.flow.steady`` bounds it there). The
gsd_cg study (docs/results/gsd_cg) lost its survival measure this way: the window started 1.2 s
into 2.5 s, a 1 s hold and a quarter revolution (0.5 s) did not fit. Warned, not refused: a
longer ``process.run_time`` or a shorter ``hold_time`` is the user's call.
"""

from __future__ import annotations

import math

from ligwf.scene.workflow import Workflow

#: the latest start of an automatic steady window, as a fraction of production
AUTO_LATEST = 0.5
#: fewer usable frames than this leave the block bootstrap and the survival measure nothing
MIN_USABLE_FRAMES = 10
#: hold times the regime map measured, in revolutions of its drum (0.1-1 s at T = 2 s):
#: held granules beat their cohesionless twin at about half a revolution
HOLD_REVOLUTIONS = (0.25, 1.0)


def held_window_warnings(wf: Workflow) -> list[str]:
    """One warning per distinct (run time, speed, dump interval) whose held-granule window is
    too short: production - steady start - hold_time - T/4 holds fewer than
    :data:`MIN_USABLE_FRAMES` dump intervals, then those of :func:`hold_period_warnings`
    (pure)."""
    settings = wf.analysis
    if settings.granules != "held":
        return []
    start = AUTO_LATEST if settings.steady_after == "auto" else float(settings.steady_after)
    out: dict[tuple[float, float, float], str] = {}
    for case, period in _granule_cases(wf):
        run, every = case.scene.process.run_time, case.scene.numerics.dump_interval
        usable = run * (1.0 - start) - settings.hold_time - period / 4.0
        frames = math.floor(max(usable, 0.0) / every + 1e-9)
        key = (run, period, every)
        if frames < MIN_USABLE_FRAMES and key not in out:
            how = ("an automatic steady window may start as late as "
                   f"{AUTO_LATEST:.0%} of production" if settings.steady_after == "auto"
                   else f"steady_after = {start:g} of production")
            out[key] = (f"analysis.hold_time = {settings.hold_time:g} s: with "
                        f"process.run_time = {run:g} s ({how}) and a quarter revolution "
                        f"({period / 4.0:.3g} s) to follow the held granules, {frames} of the "
                        f"{MIN_USABLE_FRAMES} dump intervals the granule survival needs are left "
                        f"({case.case_id}); lengthen process.run_time to at least "
                        f"{(settings.hold_time + period / 4.0 + MIN_USABLE_FRAMES * every) / (1.0 - start):.3g} s "
                        "or shorten analysis.hold_time")
    return list(out.values()) + hold_period_warnings(wf)


def hold_period_warnings(wf: Workflow) -> list[str]:
    """One warning per drum speed at which ``hold_time`` is far from half a revolution
    (outside :data:`HOLD_REVOLUTIONS`): the default 1 s is half a revolution at the regime
    map's 30 rpm only, so a slower or faster drum holds its bridges for another share of a
    turn than the one that was measured (pure)."""
    settings = wf.analysis
    out: dict[float, str] = {}
    lo, hi = HOLD_REVOLUTIONS
    for case, period in _granule_cases(wf):
        turns = settings.hold_time / period
        if not lo <= turns <= hi and period not in out:
            out[period] = (f"analysis.hold_time = {settings.hold_time:g} s is {turns:.2g} "
                           f"revolution(s) of this drum (period {period:.3g} s, "
                           f"{case.case_id}); the regime map's held granules beat their "
                           f"cohesionless twin at about half a revolution: analysis.hold_time "
                           f"= {period / 2.0:.3g} s (allowed without warning: "
                           f"{lo * period:.3g}-{hi * period:.3g} s)")
    return list(out.values())


def _granule_cases(wf: Workflow):
    """(case, rotation period s) of every case whose granules are analysed (contact dumps
    on, a wet liquid)."""
    for case in wf.cases:
        scene = case.scene
        if scene.analysis.granules and scene.liquid.wet:
            yield case, 2.0 * math.pi / scene.process.rotation.omega(scene.drum.diameter / 2.0)
