"""Settings under an old name: still read, said as one warning each before anything runs.

``scene.analysis.granules`` (the contact-dump switch) is ``scene.analysis.contact_dumps``
now: ``granules`` names the study's granule definition (the ``analysis:`` block).
"""

from __future__ import annotations

from ligwf.scene.model import RENAMED_ANALYSIS_KEY
from ligwf.scene.workflow import Workflow

OLD_PATH = f"analysis.{RENAMED_ANALYSIS_KEY}"
NEW_PATH = "analysis.contact_dumps"


def renamed_setting_warnings(wf: Workflow) -> list[str]:
    """One line per place the workflow spells a setting by its old name: the scene block,
    a swept scene field, a per-CG setting (``--set`` overrides land in these too)."""
    raw = wf.raw if isinstance(wf.raw, dict) else {}
    places = []
    scene = raw.get("scene") if isinstance(raw.get("scene"), dict) else {}
    analysis = scene.get("analysis")
    if isinstance(analysis, dict) and RENAMED_ANALYSIS_KEY in analysis:
        places.append(f"scene.{OLD_PATH}")
    sweep = raw.get("sweep") if isinstance(raw.get("sweep"), dict) else {}
    if f"scene.{OLD_PATH}" in sweep:
        places.append(f"sweep.scene.{OLD_PATH}")
    per_cg = sweep.get("per_cg") if isinstance(sweep.get("per_cg"), dict) else {}
    for cg, settings in per_cg.items():
        if isinstance(settings, dict) and {OLD_PATH, f"scene.{OLD_PATH}"} & set(settings):
            places.append(f"sweep.per_cg.{cg}.scene.{OLD_PATH}")
    return [f"{where}: renamed to {where.replace(OLD_PATH, NEW_PATH)} (the old name still "
            "works for now; granules names the analysis: block's granule definition)"
            for where in places]
