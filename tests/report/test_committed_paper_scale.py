"""docs/results/paper_scale: claims.csv recomputes from the committed case tables, in the
folder, three_revolutions/ and first_windows/ (scripts/paper_scale_results.py --check),
and the README's numbers are those of the committed report tables (the verdict against the
extrapolated CG1, the extrapolation, the cases; after 6 revolutions and, where it says what
the extensions changed, after 3 and 1.5)."""

from __future__ import annotations

import re

import pandas as pd

from ligwf.inference.size_relation import SLOPE_DEG
from ligwf.scene.grains import grains
from ligwf.scene.model import Scene
from ligwf.yamlio import read_yaml_file
from scripts.paper_scale_results import main
from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "paper_scale"
FIRST = HERE / "first_windows"
THIRD = HERE / "three_revolutions"
#: the Weber study's tables at each production length, as the README's table names them
STAGES = (("1.5 revolutions (`first_windows/`)", FIRST),
          ("3 revolutions (`three_revolutions/`)", THIRD),
          ("6 revolutions (this folder)", HERE))
README = " ".join((HERE / "README.md").read_text().split())


def test_claims_recompute_from_the_committed_cases():
    assert main(["--check"]) == 0


def _verdict() -> pd.DataFrame:
    return pd.read_csv(HERE / "weber_verdict.csv")


def test_extrapolated_cg1_and_level_means():
    e = pd.read_csv(HERE / "weber_extrapolation.csv")
    a = e[e["column"] == "angle_of_repose"].iloc[0]
    assert a["form"] == "checked" and a["levels"] == "4 6 8"
    assert (f"**The extrapolated CG1 angle of repose is {a['extrapolated']:.1f} deg "
            f"[{a['lo']:.1f}, {a['hi']:.1f}]**") in README
    assert f"lack of fit p = {a['lack_of_fit_p']:.2f}" in README
    assert f"observed order {a['observed_order']:.1f}" in README
    assert f"{abs(a['slope_per_level']):.2f} deg a level" in README and a["slope_per_level"] < 0
    means = pd.read_csv(HERE / "weber_cases.csv").groupby("cg")["angle_of_repose"].mean()
    assert " / ".join(f"{m:.2f}" for m in means) + " deg at CG4 / CG6 / CG8" in README


def test_verdict_rows_are_the_readme():
    v = _verdict()
    assert set(v["condition_state"]) == {"fails"}
    angle = v[v["criterion"] == "angle_deg"].sort_values("cg")
    assert (angle["state"] == "fail").all()
    for _, r in angle.iterrows():
        assert f"{r['value']:.2f} [{r['lo']:.2f}, {r['hi']:.2f}]" in README
    assert " / ".join(f"{b:.2f}" for b in angle["shown_within"]) in README
    spread = f"{-angle['value'].max():.1f}-{-angle['value'].min():.1f} deg"
    assert f"they lie {spread} *shallower*" in README
    guide = " ".join((ROOT / "docs" / "guide" / "scaling.md").read_text().split())
    assert f"level, {spread} below the extrapolated CG1 over 6 revolutions" in guide
    rigid = v[v["criterion"] == "rigid_share"]
    assert (rigid["state"] == "undecided").all()
    cases = pd.read_csv(HERE / "weber_cases.csv")
    assert (cases["rigid_frame_share"] == 0).all()      # "no run at any level turns as a block"
    layer = v[v["criterion"] == "flowing_layer"].sort_values("cg")
    assert (layer["state"] == "not assessed").all()
    e = pd.read_csv(HERE / "weber_extrapolation.csv").set_index("column")
    lof = e.loc["flowing_layer_thickness_mean"]
    assert lof["form"] == "rejected" and lof["lack_of_fit_p"] < 0.05
    assert all(f"lack of fit p = {lof['lack_of_fit_p']:.3f}" in n for n in layer["note"])
    thick = cases.groupby("cg")["flowing_layer_thickness_mean"].mean()
    assert (" / ".join(f"{1000 * t:.1f}" for t in thick)
            + f" mm) fails the lack-of-fit check (p = {lof['lack_of_fit_p']:.3f})") in README
    third = pd.read_csv(THIRD / "weber_verdict.csv").query("criterion == 'flowing_layer'")
    assert (third["state"] == "pass").all() and "(at 3 revolutions it passed)" in README
    norms = v[v["criterion"].isin(["profile_error", "field_error", "gsd_error"])]
    assert (norms["state"] == "not assessed").all()


def _capped(folder) -> int:
    """Runs whose steady window starts at its cap, as the verdict printed them."""
    text = (folder / "weber_summary.md").read_text()
    return sum(int(k) for k in re.findall(
        r"^- cg\d+-weber: runs too short to show a steady state: the steady window of "
        r"(\d+) of 3 CG-n runs", text, re.M))


def test_steady_windows_and_what_the_extensions_changed():
    v = _verdict().drop_duplicates("cg").set_index("cg")
    short = v["too_short_note"].fillna("")
    assert short[4.0] == "" and short[8.0] == "" and "1 of 3 CG-n runs" in short[6.0]
    assert "18 s more production" in short[6.0]
    assert "1 of 9 runs (one CG6 run) still starts" in README
    rows = []
    for name, folder in STAGES:
        e = pd.read_csv(folder / "weber_extrapolation.csv").iloc[0]
        a = pd.read_csv(folder / "weber_verdict.csv").query("criterion == 'angle_deg'")
        assert (a["state"] == "fail").all()
        rows.append(f"| {name} | {e['extrapolated']:.1f} [{e['lo']:.1f}, {e['hi']:.1f}] | "
                    + " | ".join(f"{x:.2f}" for x in a.sort_values("cg")["value"])
                    + f" | {_capped(folder)} of 9 |")
    assert "\n".join(rows) in (HERE / "README.md").read_text()
    assert [_capped(f) for _, f in STAGES] == [9, 3, 1]
    drop = (pd.read_csv(FIRST / "weber_extrapolation.csv").iloc[0]["extrapolated"]
            - pd.read_csv(HERE / "weber_extrapolation.csv").iloc[0]["extrapolated"])
    assert f"the extrapolated CG1 angle fell by {drop:.1f} deg" in README
    fr = pd.read_csv(FIRST / "weber_verdict.csv").query("criterion == 'rigid_share'")
    assert (fr["state"] == "pass").all()
    fc = pd.read_csv(FIRST / "weber_cases.csv")
    hit = fc[fc["rigid_frame_share"] > 0]
    assert list(hit["cg"]) == [6.0] and f"({hit['rigid_frame_share'].iloc[0]:.3f} of them)" in README
    for folder in (HERE, THIRD):
        assert (pd.read_csv(folder / "weber_cases.csv")["rigid_frame_share"] == 0).all()
    bond = pd.read_csv(HERE / "bond_cases.csv")
    assert bond["steady_fraction"].max() < 0.035 and "at 3 % of the run" in README
    for name in ("bond_cases.csv", "bond_verdict.csv", "bond_extrapolation.csv"):
        assert (HERE / name).read_bytes() == (THIRD / name).read_bytes()   # not extended again


def test_speedups_and_expected_excess():
    v = _verdict().drop_duplicates("cg").sort_values("cg")
    assert ", ".join(f"{s:,.0f} at CG{c:g}" for c, s in zip(v["cg"], v["speedup_core"])
                     ) in README
    expected = " / ".join(f"{SLOPE_DEG * (n - 1) / 200:.1f}" for n in (4, 6, 8))
    assert f"expected each level {expected} deg *steeper*" in README


def test_grains_in_the_readme():
    scene = Scene.model_validate(read_yaml_file(ROOT / "workflows" / "paper_scale_cg.yaml",
                                                 "workflow")["scene"])
    lifters = " / ".join(f"{grains(scene, n).lifter:.2g}" for n in (4, 6, 8))
    assert f"lifters are {lifters} grains high" in README
    cases = pd.read_csv(HERE / "weber_cases.csv")
    layer = cases.groupby("cg")["flowing_layer_thickness_mean"].mean()
    assert " / ".join(f"{t / (n * 0.001):.1f}" for n, t in layer.items()) + " grains" in README


def test_timing_is_the_recorded_one():
    import re
    text = (HERE / "timing.txt").read_text()
    wall = float(re.search(r"^([\d.]+) s wall$", text, re.M).group(1))
    planned = float(re.search(r"^estimated (\d+) min wall", text, re.M).group(1))
    first_cluster, cluster = (int(x) for x in re.findall(r"estimated (\d+) core-hours in all", text))
    assert f"Wall time of the runs: {wall:,.0f} s (the planner predicted {planned:.0f} min)" in README
    assert f"took {wall / (60 * planned):.1f}x the planner's wall time" in README
    assert f"prices it at {cluster} core-hours" in README and "[3 revolutions]" in text
    assert f"{first_cluster} for the first 1.5 revolutions" in README
    we = float(re.search(r"^([\d.]+) s wall extension weber", text, re.M).group(1))
    bo = float(re.search(r"^([\d.]+) s wall extension bond", text, re.M).group(1))
    we2 = float(re.search(r"^([\d.]+) s wall extension weber 2", text, re.M).group(1))
    assert f"{we:,.0f} s for the first extension and {we2:,.0f} s for the second" in README
    assert f"--extend-production 4.5 --no-snapshots`, {bo:,.0f} s: 3 revolutions" in README


def _claim(metric: str, cg: float) -> pd.Series:
    c = pd.read_csv(HERE / "claims.csv")
    return c[(c["metric"] == metric) & (c["cg"] == cg)].iloc[0]


def test_the_two_claims_are_the_table():
    for cg in (4.0, 6.0):
        a = _claim("angle_of_repose", cg)
        assert a["differs"] and a["lo"] > 0
        assert f"{a['bond_minus_weber']:.1f} [{a['lo']:.1f}, {a['hi']:.1f}] deg" in README
        r = _claim("rigid_frame_share", cg)
        assert f"{r['bond']:.3f}" in README and f"{r['weber']:.3f}" in README
        big = _claim("largest_cluster_fraction", cg)
        assert f"{big['bond']:.3f} [{big['bond_lo']:.3f}, {big['bond_hi']:.3f}]" in README
        assert _claim("one_granule_frame_share", cg)[["bond", "weber"]].max() == 0.0
    x = _claim("extrapolated_cg1_angle", 1.0)
    assert x["differs"] and "bond unchecked" in x["what"] and "weber checked" in x["what"]
    assert (f"extrapolate to a CG1 angle of {x['bond']:.1f} deg, {x['bond_minus_weber']:.1f} "
            f"[{x['lo']:.1f}, {x['hi']:.1f}] deg above Weber's {x['weber']:.1f}") in README
    bond = pd.read_csv(HERE / "bond_verdict.csv")
    assert set(bond[bond["criterion"] == "angle_deg"]["state"]) == {"undecided"}
