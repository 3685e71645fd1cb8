"""docs/results/resolution: the README is the text its table gives
(scripts/resolution_shift.py --check), and its shifts are those of the committed table."""

from __future__ import annotations

import pandas as pd

from scripts.resolution_shift import OUT as HERE, TABLE, main

README = " ".join((HERE / "README.md").read_text().split())


def _shift(metric: str) -> pd.DataFrame:
    t = pd.read_csv(HERE / TABLE)
    return t[t["metric"] == metric].groupby("cg")["shift"].agg(["mean", "min", "max"])


def test_readme_is_what_the_table_says():
    assert main(["--check"]) == 0


def test_angle_shifts_are_the_table():
    a = _shift("angle_of_repose")
    assert a.loc[8.0].abs().max() == 0.0           # the coarsest level: the same strips
    assert (f"moves by {a.loc[4.0, 'mean']:.2f} deg on average at CG4 (runs "
            f"{a.loc[4.0, 'min']:.2f} to +{a.loc[4.0, 'max']:.2f}) and "
            f"+{a.loc[6.0, 'mean']:.2f} at CG6 ({a.loc[6.0, 'min']:.2f} to "
            f"+{a.loc[6.0, 'max']:.2f})") in README


def test_layer_and_unmoved_metrics():
    layer = _shift("flowing_layer_thickness_mean")
    assert (f"{layer.loc[4.0, 'mean'] * 1e3:.1f} mm thicker at CG4" in README
            and f"{layer.loc[6.0, 'mean'] * 1e3:.1f} mm at CG6" in README)
    for m in ("rigid_frame_share", "steady_fraction"):
        assert _shift(m).abs().to_numpy().max() == 0.0
