"""Every committed results folder (docs/results/NAME with a README) is declared by a results
script: its README rendered from its committed tables by a ResultsFolder, or named below as
one whose README is still written by hand (issue 48 item 3: the list only shrinks; a folder
converted must leave it)."""

from __future__ import annotations

import importlib

from ligwf.api.results_folder import ResultsFolder
from ligwf.study import layout
from tests.helpers import ROOT

RESULTS = ROOT / "docs" / "results"
#: the folders whose README is still written by hand (its numbers checked, where they are,
#: by the folder's own test); verdict_rates is another helper's
HAND_WRITTEN = {"extrapolation", "gsd_cg", "paper_scale", "performance", "prediction_check",
                "verdict_rates"}


def _folders(value) -> list[ResultsFolder]:
    """The ResultsFolders a script's module-level name holds: one, a collection of them, or
    a declaration with a ``folder`` (a ladder)."""
    if isinstance(value, ResultsFolder):
        return [value]
    if isinstance(value, dict):
        value = list(value.values())
    if isinstance(value, (list, tuple)):
        return [f for v in value for f in _folders(v)]
    folder = getattr(type(value), "folder", None)
    return [value.folder] if isinstance(folder, property) else []


def declared() -> list[ResultsFolder]:
    """Every ResultsFolder the results scripts declare."""
    found = []
    for path in sorted((ROOT / "scripts").glob("*.py")):
        if "ResultsFolder" in path.read_text():
            module = importlib.import_module(f"scripts.{path.stem}")
            found += [f for value in vars(module).values() for f in _folders(value)]
    return found


def test_every_committed_readme_is_rendered_from_its_tables_or_named_hand_written():
    rendered = {f.path.resolve() for f in declared() if f.render is not None}
    with_readme = {p.parent.resolve() for p in RESULTS.glob(f"*/{layout.RESULTS_README}")}
    assert not (HAND_WRITTEN - {p.name for p in with_readme}), "a hand-written one is gone"
    still = {p.name for p in with_readme - rendered}
    assert still == HAND_WRITTEN, (f"rendered now, drop from HAND_WRITTEN: "
                                   f"{sorted(HAND_WRITTEN - still)}; neither rendered nor "
                                   f"listed: {sorted(still - HAND_WRITTEN)}")
