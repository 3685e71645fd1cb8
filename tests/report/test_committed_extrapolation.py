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


def test_new_drum_pairs_and_registered_criteria():
    v = pd.read_csv(HERE / "validation.csv")
    new = v[v["pair"] == "demo drum CG1.5-2.5"].set_index("rule")
    assert list(new["levels"]) == ["1.5 2 2.5"] * 2
    for rule, inside in (("weber", "yes"), ("bond", "**no**")):
        r = new.loc[rule]
        assert (f"| demo drum, {rule.capitalize()} | {r['form']} ({r['lack_of_fit_p']:.2f}) | "
                f"{r['extrapolated']:.2f} [{r['lo']:.2f}, {r['hi']:.2f}] | "
                f"{r['cg1_mean']:.2f} | {inside} |") in README
    checked = new[new["form"] == "checked"]
    k, n = int(checked["inside"].sum()), len(checked)
    assert f"in **{k} of {n}** pairs that pass the checks" in README
    assert k / n < 0.9 and "(registered >= 90 %): **not met**" in README
    weber = new.loc["weber"]
    assert weber["form"] == "checked" and "(**1 of 1**): **met**" in README
    assert weber["half_width"] > 1.0
    assert f"half-width is **{weber['half_width']:.2f}** deg" in README
    pooled = v[v["rule"] == "weber"]
    assert f"inside in {int(pooled['inside'].sum())} of {len(pooled)} pairs, Bond's in " \
           f"{int(v[v['rule'] == 'bond']['inside'].sum())} of 4" in README


def test_demo_drum_report_tables_are_the_readme():
    e = pd.read_csv(HERE / "demo_drum_extrapolation.csv")
    row = e[(e["rule"] == "weber - bond") & (e["column"] == "angle_of_repose")].iloc[0]
    assert f"by {row['extrapolated']:.2f} [{row['lo']:.2f}, {row['hi']:.2f}] deg" in README
    bond = e[(e["rule"] == "bond") & (e["column"] == "angle_of_repose")].iloc[0]
    assert f"misses CG1 by {bond['extrapolated'] - bond['cg1_measured']:.1f} deg" in README
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
