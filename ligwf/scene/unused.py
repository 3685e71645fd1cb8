"""Settings that are legal but do nothing: said as warnings before anything runs (issue 32:
nothing silent)."""

from __future__ import annotations

from ligwf.scene.workflow import Workflow


def unused_setting_warnings(wf: Workflow) -> list[str]:
    """Settings that are legal but would do nothing (surely not what the user meant): a
    ``sweep.replicas`` count for a CG level the sweep does not run (e.g. after ``--set
    sweep.cg_levels=...``), an ``accept:`` block with every tolerance null."""
    out = []
    replicas = (wf.raw.get("sweep") or {}).get("replicas") if isinstance(wf.raw, dict) else None
    levels = sorted({c.cg for c in wf.cases})
    if isinstance(replicas, dict):
        for key in replicas:
            try:
                cg = float(key)
            except (TypeError, ValueError):
                continue
            if cg not in levels:
                out.append(f"sweep.replicas.{cg:g} = {replicas[key]}: CG level {cg:g} is not "
                           f"swept (sweep.cg_levels [{', '.join(f'{c:g}' for c in levels)}]): the count "
                           "is not used")
    budget = wf.accept.model_dump()
    if all(v is None for v in budget.values()):
        out.append(f"accept: every tolerance is null ({', '.join(budget)}): no criterion is "
                   "left, so no CG level can be accepted or refused; drop the accept: block "
                   "for the defaults or give at least one tolerance")
    return out
