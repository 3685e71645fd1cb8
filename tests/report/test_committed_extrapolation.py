"""docs/results/extrapolation: its tables recompute from the committed studies (the
results script's --check), the size relation's constants in ligwf are the committed fit,
and the README's numbers are the tables'."""

from __future__ import annotations

import re
import subprocess
import sys

import pandas as pd
import pytest

from ligwf.inference import size_relation as sr
from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "extrapolation"
#: the README with its line breaks as spaces (a number may sit at a wrap)
README = " ".join((HERE / "README.md").read_text().split())


def test_tables_recompute_from_the_committed_studies():
    r = subprocess.run([sys.executable, str(ROOT / "scripts" / "extrapolation_results.py"),
                        "--check", "--no-figure"], capture_output=True, text=True, cwd=ROOT)
    assert r.returncode == 0, r.stdout + r.stderr


def test_the_package_carries_the_committed_fit():
    fit = pd.read_csv(HERE / "size_fit.csv").iloc[0]
    assert fit["fit"] == "weber, every study"
    assert (sr.SLOPE_DEG, sr.SLOPE_DEG_LO, sr.SLOPE_DEG_HI) == (
        round(fit["slope_deg"], 1), round(fit["lo"], 1), round(fit["hi"], 1))
    assert sr.FITTED_D_OVER_ND == (round(fit["d_over_nd_min"], 1),
                                   round(fit["d_over_nd_max"], 1))
    m = re.search(r"\*\*([\d.]+) deg x \(n - 1\) d / D \[([\d.]+), ([\d.]+)\]\*\* \(weighted "
                  r"fit through the origin, (\d+) rows of 4 studies, Birge ratio ([\d.]+)", README)
    assert m and float(m.group(1)) == sr.SLOPE_DEG and int(m.group(4)) == fit["rows"]
    assert float(m.group(5)) == round(fit["birge"], 2)


def test_readme_bond_rows_are_the_table():
    rows = pd.read_csv(HERE / "size_relation.csv")
    bond = rows[rows["rule"] == "bond"]
    flow = sorted(round(v, 1) for v in bond[bond["bed"] == "flow"]["excess_deg"])
    binder = sorted(round(v, 1) for v in bond[bond["bed"] == "binder"]["excess_deg"])
    assert f"+{flow[0]} and +{flow[1]} deg at CG2 on the flow beds" in README
    assert f"{binder[1]} and {binder[0]} on the binder beds" in README


def _cells() -> pd.DataFrame:
    return pd.read_csv(HERE / "coverage.txt", sep="\t", comment="#")


def test_registered_coverage_is_met_and_said():
    c = _cells()
    prior = c[c["curvature"] == "prior"]["coverage95"]
    assert prior.between(0.92, 0.99).all()          # the registered criterion holds
    assert f"**{prior.min():.3f}-{prior.max():.3f}**" in README
    src = c[(c["curvature"] == "prior") & (c["design"] == "source drum CG4/6/8")]["coverage95"]
    assert f"CG4/6/8 design in {src.min():.3f}-{src.max():.3f}" in README
    two = c[(c["curvature"] == "+2 sd") & (c["design"] == "small drum CG2-4")]
    assert f"in {two['coverage95'].min():.3f}-{two['coverage95'].max():.3f} of trials" in README
    lof = pd.to_numeric(two["lof_rejected"])
    assert f"flags {lof.min():.3f}-{lof.max():.3f}" in README


@pytest.mark.parametrize("rule, word", [("weber", "**3 of 3**"), ("bond", "**0 of 3**")])
def test_committed_pairs_counts(rule, word):
    v = pd.read_csv(HERE / "validation.csv")
    sub = v[(v["rule"] == rule) & v["pair"].isin(["ladder", "ladder cap_80min", "we_vs_bo"])]
    assert (sub["form"] == "unchecked").all()
    assert f"**{int(sub['inside'].sum())} of {len(sub)}**" == word
    assert f"{rule.capitalize()}'s" in README and word in README
    if rule == "weber":
        assert (f"half-widths {sub['half_width'].min():.2f}-{sub['half_width'].max():.2f}"
                in README)
    else:
        assert (f"extrapolated {sub['extrapolated'].min():.1f}-{sub['extrapolated'].max():.1f}"
                in README)


NEW = {"demo drum CG1.5-2.5": "demo drum", "new drum CG1.5-2.5": "new drum"}


def test_new_drum_pairs_and_registered_criteria():
    v = pd.read_csv(HERE / "validation.csv")
    new = v[v["pair"].isin(NEW)]
    assert len(new) == 4 and set(new["levels"]) == {"1.5 2 2.5"}
    for _, r in new.iterrows():
        inside = "yes" if r["inside"] else "**no**"
        assert (f"| {NEW[r['pair']]}, {r['rule'].capitalize()} | {r['form']} "
                f"({r['lack_of_fit_p']:.2f}) | {r['extrapolated']:.2f} [{r['lo']:.2f}, "
                f"{r['hi']:.2f}] | {r['cg1_mean']:.2f} | {inside} |") in README
    checked = new[new["form"] == "checked"]
    k, n = int(checked["inside"].sum()), len(checked)
    assert f"in **{k} of {n}** pairs that pass the checks" in README
    assert k / n < 0.9 and "(registered >= 90 %): **not met**" in README
    assert (new[new["rule"] == "bond"]["inside"] == False).all()      # noqa: E712
    for _, r in new[new["rule"] == "bond"].iterrows():
        assert f"{r['extrapolated'] - r['cg1_mean']:.1f} deg" in README
    weber = new[new["rule"] == "weber"].set_index("pair")
    assert (weber["form"] == "checked").all() and "(**2 of 2**): **met**" in README
    demo, fresh = weber.loc["demo drum CG1.5-2.5"], weber.loc["new drum CG1.5-2.5"]
    assert demo["half_width"] > 1.0 >= fresh["half_width"]
    assert (f"half-width is **{demo['half_width']:.2f}** deg on the demo drum and "
            f"**{fresh['half_width']:.2f}** on the new one") in README
    assert "**not met**, 1 of 2" in README
    pooled = v[v["rule"] == "weber"]
    bond = v[v["rule"] == "bond"]
    assert (f"inside in {int(pooled['inside'].sum())} of {len(pooled)} pairs, Bond's in "
            f"{int(bond['inside'].sum())} of {len(bond)}") in README


def test_new_drum_report_tables_and_the_size_relation_printed_before_its_runs():
    e = pd.read_csv(HERE / "new_drum_extrapolation.csv")
    row = e[(e["rule"] == "weber - bond") & (e["column"] == "angle_of_repose")].iloc[0]
    assert row["hi"] < 0                                   # past the check's edge
    assert (f"on the new drum by {row['extrapolated']:.2f} [{row['lo']:.2f}, "
            f"{row['hi']:.2f}] deg") in README
    cases = pd.read_csv(HERE / "new_drum_cases.csv")
    spread = cases[cases["rule"] == "weber"].groupby("cg")["angle_of_repose"].std()
    assert f"(up to {spread.max():.1f} deg at CG{spread.idxmax():g})" in README
    rows = [r for r in sr.excess_rows(cases, "new drum", 0.0025 / 0.07) if r["rule"] == "weber"]
    expected = ", ".join(f"{sr.SLOPE_DEG * r['x']:.1f} [{sr.SLOPE_DEG_LO * r['x']:.1f}, "
                         f"{sr.SLOPE_DEG_HI * r['x']:.1f}]" for r in rows)
    assert expected.replace(", 5.3", " and 5.3") in README
    measured = ", ".join(f"{r['excess_deg']:.2f}" for r in rows)
    assert f"Measured: {measured.replace(', 5.', ' and 5.')} deg" in README
    inside = [sr.SLOPE_DEG_LO * r["x"] <= r["excess_deg"] <= sr.SLOPE_DEG_HI * r["x"]
              for r in rows]
    assert inside == [True, False, True]
    assert "inside at CG1.5 and CG2.5, above the interval at CG2" in README


def test_demo_drum_report_tables_are_the_readme():
    e = pd.read_csv(HERE / "demo_drum_extrapolation.csv")
    row = e[(e["rule"] == "weber - bond") & (e["column"] == "angle_of_repose")].iloc[0]
    assert f"by {row['extrapolated']:.2f} [{row['lo']:.2f}, {row['hi']:.2f}] deg" in README
    bond = e[(e["rule"] == "bond") & (e["column"] == "angle_of_repose")].iloc[0]
    assert (f"miss CG1, by {bond['extrapolated'] - bond['cg1_measured']:.1f} deg on the demo "
            "drum") in README
    cases = pd.read_csv(HERE / "demo_drum_cases.csv")
    spread = cases[cases["rule"] == "weber"].groupby("cg")["angle_of_repose"].std()
    assert f"(up to {spread.max():.1f} deg between seeds at CG{spread.idxmax():g})" in README


def test_new_weber_rows_beside_the_fit():
    cases = pd.read_csv(HERE / "demo_drum_cases.csv")
    rows = [r for r in sr.excess_rows(cases, "demo drum", 0.002 / 0.05) if r["rule"] == "weber"]
    got = ", ".join(f"{r['excess_deg']:.2f} +- {r['excess_se']:.2f}" for r in rows)
    assert got.replace(", 4", " and 4") in README
    assert ", ".join(f"{r['x']:.2f}" for r in rows).replace(", 0.06", " and 0.06") in README
    want = ", ".join(f"{sr.SLOPE_DEG * r['x']:.2f}" for r in rows)
    assert want.replace(", 5", " and 5") in README


def test_the_scaling_guide_quotes_the_new_drums():
    guide = " ".join((ROOT / "docs" / "guide" / "scaling.md").read_text().split())
    v = pd.read_csv(HERE / "validation.csv")
    new = v[v["pair"].isin(NEW)].set_index(["pair", "rule"])
    order = list(NEW)
    weber = [new.loc[(p, "weber")] for p in order]
    bond = [new.loc[(p, "bond")] for p in order]
    assert all(r["inside"] for r in weber) and not any(r["inside"] for r in bond)
    assert "Weber's measured CG1 lay inside its interval on both" in guide
    assert ("half-widths " + " and ".join(f"{r['half_width']:.2f}" for r in weber)
            + " deg: the registered 1 deg held on one") in guide
    assert sum(r["half_width"] <= 1 for r in weber) == 1
    assert all(r["form"] == "checked" for r in bond)
    assert ("missed CG1 on both (by " + " and ".join(
        f"{r['extrapolated'] - r['cg1_mean']:.1f}" for r in bond) + " deg)") in guide
