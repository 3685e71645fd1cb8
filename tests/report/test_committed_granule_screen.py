"""docs/results/granule_screen (issue 47 item 3): the README and the derived verdict are what
the committed tables give (the script's --check), and every registered point, pick and
criterion reads again from the measures in those tables."""

from __future__ import annotations

import sys

import numpy as np
import pandas as pd
import pytest

from ligwf.analysis.granules import screen
from ligwf.analysis.granules.growth import hac_slope
from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "granule_screen"
sys.path.insert(0, str(ROOT / "scripts"))
import granule_screen_results as gs  # noqa: E402


def test_readme_and_verdict_are_the_committed_tables():
    assert gs.main(["--check"]) == 0


def test_phase1_points_and_pick_read_from_the_measures():
    cond = pd.read_csv(HERE / gs.CONDITIONS_TABLE)
    assert sorted(cond.condition) == ["S1", "S2", "S3", "S4"]
    for _, r in cond.iterrows():
        done = r.status == "done"
        assert r.exists == (done and r.share_10 >= 0.02)
        assert r.survives == (done and r.survival >= 0.5)
        assert r.grows == (done and r.slope_low > 0)
        assert r.comoves == (done and r.comove_ratio <= 0.5)
        # amendment 1: a wet mass spanning the slice in > 10 % of start frames scores 0
        wet_mass = bool(done and r.spanning_frames > 0.10)
        assert r.wet_mass == wet_mass
        assert r.points == (0 if wet_mass else int(r.exists + r.survives + r.grows + r.comoves))
        if not done:
            assert r.points == 0 and isinstance(r.reason, str) and r.reason
    best = cond.sort_values(["points", "share_10_last"], ascending=False).iloc[0]
    assert cond.loc[cond["rank"] == 1, "condition"].item() == best.condition == "S3"
    assert f"**{best.condition}**" in (HERE / "README.md").read_text()


def test_phase1_rank_is_the_registered_rule_on_the_committed_rows():
    cond = pd.read_csv(HERE / gs.CONDITIONS_TABLE)
    again = screen.ranked(cond.drop(columns="rank").sample(frac=1.0, random_state=1))
    assert list(again["condition"]) == list(cond["condition"])
    assert list(again["rank"]) == list(cond["rank"]) == [1, 2, 3, 4]


def test_phase1_slope_is_its_rows():
    rows = pd.read_csv(HERE / gs.GROWTH_ROWS)
    cond = pd.read_csv(HERE / gs.CONDITIONS_TABLE).set_index("condition")
    lag = int(round(screen.SETTINGS.hold_time / screen.SETTINGS.stride)) + 1
    for name, g in rows.groupby("condition"):
        fit = hac_slope(g["time"].to_numpy(), g["share_10"].to_numpy(), lag)
        assert fit.slope == pytest.approx(cond.loc[name, "slope_per_s"], rel=1e-4, abs=1e-9)
        assert g.share_10.mean() == pytest.approx(cond.loc[name, "share_10"], rel=1e-4)


def test_phase2_verdict_counts_its_seeds():
    if not (HERE / gs.PHASE2_SEEDS).is_file():
        assert "Not run yet." in (HERE / "README.md").read_text()
        return
    seeds = pd.read_csv(HERE / gs.PHASE2_SEEDS)
    verdict = pd.read_csv(HERE / gs.PHASE2_VERDICT).set_index("criterion")
    assert len(seeds) == screen.SEEDS
    for _, s in seeds[seeds.complete].iterrows():
        ratio = 0.2 * s.share_10
        assert s.pass_control == bool(s.share_10 >= 0.02 and s.cohesionless_share_10 <= ratio
                                       and s.uniform_share_10 <= ratio)
        assert s.pass_survival == bool(s.survival >= 0.5)
        assert s.pass_growth == bool(s.slope_low > 0)
        assert s.pass_comovement == bool(s.comove_ratio <= 0.5)
    for col in screen.REGISTERED + screen.REPORTED:
        k = int(seeds[col].sum())
        name = col.removeprefix("pass_")
        assert verdict.loc[name, "seeds_pass"] == k
        assert bool(verdict.loc[name, "passes"]) == (k >= 4)
    found = all(verdict.loc[c.removeprefix("pass_"), "passes"] for c in screen.REGISTERED)
    assert bool(verdict.loc["finds_growth", "passes"]) == found
    text = (HERE / "README.md").read_text()
    assert ("**The screen finds growth**" in text) == found


def test_the_phase2_rule_fails_a_seed_without_its_null():
    """A seed whose uniform twin is missing is not evidence: it fails every criterion."""
    rows = pd.read_csv(HERE / gs.GROWTH_ROWS)
    s3 = rows[rows.condition == "S3"].drop(columns="condition").copy()
    s3["case_id"] = "cg1-none-r0"
    twin = s3.copy()
    twin["case_id"] = "cg1-none-r0_cohesionless"
    twin["share_10"] = 0.0
    flows = pd.DataFrame({"case_id": ["cg1-none-r0", "cg1-none-r0_cohesionless"] * 2,
                          "time": [1.0, 1.0, 2.0, 2.0], "angle_of_repose": 40.0,
                          "rigid_fraction": 0.0, "wet_share": [0.05, 0.0, 1.0, 0.0]})
    seeds = screen.phase2_seeds(pd.concat([s3, twin]), flows)
    assert len(seeds) == screen.SEEDS and not seeds.complete.any()
    verdict = screen.phase2_verdict(seeds).set_index("criterion")
    assert not verdict.passes.any() and (verdict.seeds_pass == 0).all()
    # with both nulls present the control criterion is judged on each of them
    uni = s3.copy()
    uni["case_id"] = "cg1-none-r0_uniform"
    flows2 = pd.concat([flows, flows[flows.case_id == "cg1-none-r0_cohesionless"]
                        .assign(case_id="cg1-none-r0_uniform")])
    seeds = screen.phase2_seeds(pd.concat([s3, twin, uni]), flows2)
    r0 = seeds.set_index("seed").loc["cg1-none-r0"]
    assert r0.complete and r0.pass_control_cohesionless and not r0.pass_control_uniform
    assert not r0.pass_control and np.isclose(r0.uniform_share_10, r0.share_10)


def test_what_the_engine_lacks_names_each_failed_criterion_with_its_numbers():
    seeds = pd.DataFrame([{"seed": f"cg1-none-r{r}", "complete": True, "share_10": 0.3,
                           "uniform_share_10": 0.25, "cohesionless_share_10": 0.0,
                           "survival": 0.3, "slope_per_s": 0.002, "comove_ratio": 0.6,
                           "wet_share_start": 0.06, "wet_share_end": 1.0} for r in range(5)])
    text = "\n".join(gs.lacks(seeds, ["control", "survival", "comovement"]))
    assert "**placement makes no difference**: the uniform twins at the same mean content " \
        "hold share_10 0.25 (5 of 5 seeds" in text
    assert "the cohesionless twins hold 0 (within 1/5 in every seed)" in text
    assert "mean survival 0.3" in text and "co-movement ratio 0.6" in text
    assert "does not grow" not in text and "from 0.06 to 1" in text
    assert gs.lacks(seeds.iloc[0:0], ["survival"])[0].startswith("- No seed")


def test_phase1_rows_are_what_the_screen_makes_of_the_committed_growth_rows():
    """screen.condition_row on each condition's committed start frames gives its committed
    measures and points (the frame flows are not committed: a stand-in gives the
    liquid's columns, which are not compared)."""
    rows = pd.read_csv(HERE / gs.GROWTH_ROWS)
    cond = pd.read_csv(HERE / gs.CONDITIONS_TABLE).set_index("condition")
    flows = pd.DataFrame({"time": [0.0, 2.0], "wet_share": [1.0, 0.5],
                          "angle_of_repose": [40.0, 40.0]})
    compared = ["share_10", "share_10_last", "share_10_first_rev", "d50_particles", "largest",
                "survival", "comove_ratio", "slope_per_s", "slope_low", "slope_high",
                "spanning_frames", "wall_share", "bed_wall_share", "revolutions"]
    for name, g in rows.groupby("condition"):
        c = cond.loc[name]
        row = screen.condition_row(name, c.model, c.liquid, g.drop(columns="condition"), flows,
                                   c.status, 60.0 * c.core_minutes, str(c.reason))
        assert row["start_frames"] == c.start_frames
        for col in compared:
            assert row[col] == pytest.approx(c[col], rel=1e-4, abs=1e-9, nan_ok=True), (name, col)
        for col in ("exists", "survives", "grows", "comoves", "wet_mass", "points"):
            assert row[col] == c[col], (name, col)
