"""docs/results/granules (the binder study that was the demo until 2026-12-04): its README is
the text its committed tables give (scripts/kept_results.py --check), and what its prose
says of the verdict is what the verdict table holds."""

from __future__ import annotations

import pandas as pd

from scripts.kept_results import GRANULES, main


def test_readme_is_what_the_tables_say():
    assert main(["--check"]) == 0
    assert GRANULES.readme.read_text() == GRANULES.text()


def test_the_prose_reads_the_verdict():
    verdict = pd.read_csv(GRANULES.path / "verdict.csv").set_index(["condition", "criterion"])
    # Bond-CG2 fails the continuum-field criterion
    assert verdict.loc[("cg2-bond", "field_error"), "state"] == "fail"
    # We-CG2 is undecided on every flow criterion; no level meets the budget
    weber = verdict.loc["cg2-weber"]
    assert set(weber.loc[["angle_deg", "profile_error", "rigid_share", "flowing_layer"],
                         "state"]) == {"undecided"}
    assert not (verdict["cheapest"].astype(str) == "True").any()
    # the GSD criterion is not assessed
    assert set(verdict.xs("gsd_error", level="criterion")["state"]) == {"not assessed"}
