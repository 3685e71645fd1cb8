"""docs/results/verdict_rates: the designs users run (bench_coverage.py --designs), registered
before the run. The README's numbers are those of the committed rates.txt, its checks say
what the file's check lines say (a failed registered check stays failed), and the file's
cells give its check lines."""

from __future__ import annotations

import re

from scipy import stats

from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "verdict_rates"
TEXT = (HERE / "rates.txt").read_text()
README = " ".join((HERE / "README.md").read_text().split())


def _lower(rate: float, trials: int) -> float:
    k = round(rate * trials)
    return 0.0 if k == 0 else float(stats.beta.ppf(0.05, k, trials - k + 1))


def _section(title: str) -> str:
    return TEXT.split(title, 1)[1].split("\ncheck", 1)[0]


def _rows(title: str) -> list[list[float]]:
    """The cells of a design: [CG-n runs, CG1 runs, *the line's numbers]."""
    return [[float(v) for v in re.findall(r"-?\d+(?:\.\d+)?", line)]
            for line in _section(title).splitlines() if "|" in line and re.search(r"\d", line)]


def test_made_by_the_registered_command_after_its_registration():
    first = TEXT.splitlines()[0]
    registered = re.search(r"^    (nice -n 19 .*) > docs/results/verdict_rates/rates.txt$",
                           (HERE / "README.md").read_text(), re.M).group(1)
    assert first.startswith("# " + registered.replace(" > docs", ""))
    assert "4000 studies a cell (2000 for the family and levels cells)" in TEXT
    # the registration precedes the result section in the README
    assert README.index("Registered before the run") < README.index("## Result")


def test_check_lines_recompute_from_the_cells():
    trials, level_trials = 4000, 2000
    unequal = _rows("budget in frame sd)")
    assert len(unequal) == 36
    cover = [v for r in unequal for v in r[5:7]]
    inside = sum(0.92 <= v <= 0.99 for v in cover)
    assert (f"check unequal intervals: {inside} of 72 cells in [0.92, 0.99] "
            f"({min(cover):.3f}-{max(cover):.3f}): FAILS") in TEXT
    rates = [v for r in unequal for v in r[7:9]]
    assert f"check unequal rates: at most {max(rates):.4f}; 0 of 72" in TEXT
    assert all(_lower(v, trials) <= 0.05 for v in rates)
    zero = _rows("the budget 0.05)")
    above = [r for r in zero if _lower(r[4], trials) > 0.05]
    assert len(zero) == 8 and len(above) == 1
    assert (f"at most {max(r[4] for r in zero):.4f} (registered rule: up to "
            f"{max(r[5] for r in zero):.4f}); 1 of 8 shown above 0.05: FAILS") in TEXT
    fam = _rows("each on its budget")
    assert len(fam) == 6 and all(_lower(r[5], level_trials) <= 0.05 for r in fam)
    lev = _rows("each with a criterion on the budget")
    assert len(lev) == 6 and all(_lower(r[3], level_trials) <= 0.2 for r in lev)
    assert "summary: 2 of 4 registered checks hold" in TEXT


def test_readme_numbers_are_the_file():
    assert "**2 of 4 registered checks hold.**" in README
    unequal = _rows("budget in frame sd)")
    cover = [v for r in unequal for v in r[5:7]]
    outside = [v for v in cover if not 0.92 <= v <= 0.99]
    assert all(v > 0.99 for v in outside)
    assert (f"{72 - len(outside)} of 72 interval cells of the unequal designs lie in "
            f"[0.92, 0.99]; all {len(outside)} outside lie above 0.99 "
            f"({min(cover):.3f}-{max(cover):.3f} in all)") in README
    six = [v for r in unequal if r[0] == 6.0 for v in r[5:7]]
    assert f"{sum(v > 0.99 for v in six)} of the {len(six)} cells of 6 vs 2 are above 0.99" \
        in README
    wide = [r[5] for r in unequal if r[0] == 24.0 and r[2] == 2.0]
    assert all(v > 0.99 for v in wide) and len(outside) == sum(v > 0.99 for v in six) + len(wide)
    assert f"so are the {len(wide)} cells of the 95 % interval of 24 vs 3" in README
    rates = [v for r in unequal for v in r[7:9]]
    assert f"wrong pass and wrong fail at most {max(rates):.4f}" in README
    zero = _rows("the budget 0.05)")
    worst = max(zero, key=lambda r: r[4])
    assert worst[:3] == [60.0, 60.0, 0.2]
    assert f"passes wrongly in {worst[4]:.4f} of studies" in README
    rule3 = next(r for r in zero if r[0] == 60.0 and r[2] == 1.0)
    assert f"reads 1 in 5 % of runs: {rule3[4]:.4f}" in README
    assert all(r[4] == 0.0 for r in zero if r[1] <= 3.0)                # 2- and 3-run arms
    assert f"passed wrongly in up to {max(r[5] for r in zero):.4f}" in README
    fam = _rows("each on its budget")
    assert (f"decided in at most {max(r[5] for r in fam):.4f} of studies (the registered "
            f"rule: {min(r[6] for r in fam):.4f}-{max(r[6] for r in fam):.4f})") in README
    lev = _rows("each with a criterion on the budget")
    assert f"meets in at most {max(r[3] for r in lev):.4f} of studies" in README
    assert f"it would be at most {max(r[5] for r in lev):.4f}" in README
    for n, state in ((1, "fails"), (2, "fails"), (3, "holds"), (4, "holds")):
        assert re.search(rf"{n}\. [^:]+: \*\*{state}\*\*", README), n


def test_second_run_numbers_are_its_file():
    text = (HERE / "rates_2.txt").read_text()
    assert "--seed 20261208" in text.splitlines()[0]
    assert "summary: 3 of 4 registered checks hold" in text
    assert "**3 of 4 registered checks hold.** Check 2 now holds" in README
    unequal = re.search(r"check unequal intervals: (\d+) of 72 cells in \[0.92, 0.99\] "
                        r"\(([\d.]+-[\d.]+)\): FAILS", text)
    assert (f"{unequal.group(1)} of 72 interval cells in [0.92, 0.99] ({unequal.group(2)})"
            in README)
    for label, quoted in (("check unequal rates: at most ([\\d.]+)", "are at most {}"),
                          ("check all-zero wrong pass: at most ([\\d.]+)",
                           "passes wrongly in at most {} of studies"),
                          ("check family-wise wrong decision: at most ([\\d.]+)",
                           "family-wise at most {}"),
                          ("check cheapest level disclosed: at most ([\\d.]+)",
                           "meets in at most {} of studies")):
        value = re.search(label, text).group(1)
        assert quoted.format(value) in README, label
    zero = re.findall(r"^60 vs 60 +([\d.]+) +[\d.]+ \| +([\d.]+)", text, re.M)
    assert dict(zero) == {"1.0": "0.0495", "0.2": "0.0000"}


def test_third_run_numbers_are_its_file():
    text = (HERE / "rates_3.txt").read_text()
    assert "--seed 20261209" in text.splitlines()[0] and "behrens-fisher" in text.splitlines()[0]
    assert "summary: 4 of 4 registered checks hold" in text
    assert "**4 of 4 registered checks hold.** Check 1: 72 of 72" in README
    span = re.search(r"check unequal intervals: 72 of 72 cells in \[0.92, 0.99\] "
                     r"\(([\d.]+-[\d.]+)\): holds", text).group(1)
    assert f"lie in [0.92, 0.99] ({span}) with the Behrens-Fisher interval" in README
    rates = re.search(r"check unequal rates: at most ([\d.]+); 0 of 72", text).group(1)
    assert f"wrong pass and wrong fail at most {rates}, none shown above 0.05" in README
    cells = [r for r in re.findall(r"^ *24 vs 3 +([\d.]+) +([\d.]+) +([\d.]+) \| +[\d.]+ +"
                                   r"[\d.]+ \| +([\d.]+) +([\d.]+)$", text, re.M)]
    above = sorted(float(c[3]) for c in cells if float(c[3]) > 0.05)     # wrong passes
    assert len(above) == 2 and all(float(c[4]) <= 0.05 for c in cells)
    assert all(c[0] == "0.5" for c in cells if float(c[3]) > 0.05)
    assert (f"above 0.05, {above[0]:.4f} and {above[1]:.4f}, both 24 vs 3" in README
            and f"bounds of {_lower(above[0], 4000):.2g} and {_lower(above[1], 4000):.2g}"
            in README)
    for label, quoted in (("check all-zero wrong pass: at most ([\\d.]+)",
                           "all-zero shares at most {}"),
                          ("check family-wise wrong decision: at most ([\\d.]+)",
                           "family-wise at most {}"),
                          ("check cheapest level disclosed: at most ([\\d.]+)",
                           "meets in at most {} of studies")):
        assert quoted.format(re.search(label, text).group(1)) in README, label


def test_profile_bins_run_is_what_the_readme_says():
    """profiles.txt (bench_coverage --profiles, registered before it): the registered
    command, its four check lines as the README reports them, and the numbers quoted."""
    text = (HERE / "profiles.txt").read_text()
    registered = re.search(r"^    (nice -n 19 .*--profiles.*) > docs/results/verdict_rates/"
                           r"profiles.txt$", (HERE / "README.md").read_text(), re.M).group(1)
    assert text.splitlines()[0].startswith("# " + registered)
    rows = [line.split() for line in text.splitlines() if "|" in line and " vs " in line]
    assert len(rows) == 36
    cells = {(r[0], r[1] + " vs " + r[3], float(r[4])): [float(v) for v in
             (r[6], r[7], r[8], r[10], r[11], r[12])] for r in rows}
    corr = [v for k, v in cells.items() if k[0] == "correlated"]
    two = [v for k, v in cells.items() if k[0] == "correlated" and k[1] == "2 vs 2"]
    rest = [v for k, v in cells.items() if k[0] == "correlated" and k[1] != "2 vs 2"]
    indep = [v for k, v in cells.items() if k[0] == "independent"]
    assert (min(v[0] for v in two), max(v[0] for v in two)) == (0.907, 0.914)
    assert (min(v[0] for v in rest), max(v[0] for v in rest)) == (0.968, 0.994)
    assert max(v[2] for v in rest) == 0.065 and max(v[1] for v in rest) <= 0.032
    assert (min(v[3] for v in corr), max(v[3] for v in corr)) == (0.662, 0.759)
    assert (min(v[0] for v in indep), max(v[0] for v in indep)) == (0.951, 0.983)
    assert max(max(v[1], v[2]) for v in indep) == 0.0488
    checks = re.findall(r"^check (\d) .*: (holds|FAILS)$", text, re.M)
    assert checks == [("1", "FAILS"), ("2", "FAILS"), ("3", "holds"), ("4", "holds")]
    assert "summary: 2 of 4 registered checks hold" in text
    assert "**2 of 4 registered checks hold.**" in README


def _registered_run(name: str, command: str) -> tuple[str, str, str]:
    """A profiles run's file, the README and the command registered for it (the README's
    indented line matching ``command`` whose output is ``name``); the file's first line is
    that command, followed by when and where it ran."""
    text = (HERE / name).read_text()
    raw = (HERE / "README.md").read_text()
    registered = re.search(rf"^    ({command}) > docs/results/verdict_rates/{re.escape(name)}$",
                           raw, re.M).group(1)
    assert text.splitlines()[0].startswith("# " + registered + " ")
    return text, raw, registered


def test_simulated_fail_test_run_is_what_the_readme_says():
    """profiles_2.txt (bench_coverage --profiles-2, registered before it): the registered
    command on its first line, the check lines recomputed from its cells (designs of >= 6
    runs counted, a rate shown above 0.05 by its lower 95 % Clopper-Pearson bound) and the
    numbers the README quotes."""
    text, _, registered = _registered_run("profiles_2.txt", r"nice -n 19 .*--profiles-2.*")
    rows = [line.split() for line in text.splitlines() if "|" in line and " vs " in line]
    assert len(rows) == 36
    cells = {(r[0], int(r[1]) + int(r[3]), r[1] + " vs " + r[3], float(r[4])):
             [float(v) for v in (r[6], r[7], r[8], r[10], r[11], r[12])] for r in rows}
    assert _profile_checks(cells, text, 4000) == [False, True, True, True]
    assert "summary: 3 of 4 registered checks hold" in text
    assert "**3 of 4 registered checks hold.**" in README
    corr = [v for k, v in cells.items() if k[0] == "correlated" and k[1] >= 6]
    indep = [v for k, v in cells.items() if k[0] == "independent" and k[1] >= 6]
    assert f"at most {max(v[2] for v in corr):.4f} (6 vs 2, offset 1)" in README
    assert f"Wrong pass at most {max(v[1] for v in corr):.4f}" in README
    assert f"wrongly up to {max(v[5] for v in corr):.4f} (3 vs 3, offset 3" in README
    assert "(0.970-0.997)" in README and f"({min(v[0] for v in indep):.3f}-" in README
    assert f"{max(v[1] for v in indep):.4f} (pass) and {max(v[2] for v in indep):.4f}" in README


def test_the_analysis_guide_quotes_both_profile_runs():
    """docs/guide/analysis.md's profile sentence: the old rule's worst wrong fail on
    correlated bins at 3 runs an arm or more (profiles.txt), the simulated test's
    (profiles_2.txt check 2) and its upper bound's largest coverage (check 1)."""
    import re
    guide = " ".join((ROOT / "docs" / "guide" / "analysis.md").read_text().split())
    old = (HERE / "profiles.txt").read_text().splitlines()
    rows = [line.split() for line in old if line.startswith(" correlated")
            and line.split()[1] != "2"]
    worst_old = max(float(r[8]) for r in rows)       # rule correlated: cover, pass, fail
    new = (HERE / "profiles_2.txt").read_text()
    fail = float(re.search(r"check 2 .*?fail ([\d.]+)\)", new).group(1))
    cover = re.search(r"check 1 .*?\(([\d.]+)-([\d.]+)\)", new).group(2)
    assert (f"failed wrongly in up to {100 * worst_old:.1f} % of correlated studies, the "
            f"simulated test in at most {100 * fail:.1f} %") in guide
    assert f"over-covers there, up to {cover}," in guide


def _profile_checks(cells: dict, text: str, trials: int) -> list[bool]:
    """The four registered checks of a profiles_N.txt recomputed from its cells (designs of
    >= 6 runs counted; per bins, coverage in [0.92, 0.99] and no wrong pass or wrong fail
    shown above 0.05 by its lower 95 % Clopper-Pearson bound over ``trials``), held to the
    file's own check lines."""
    holds = []
    for bins in ("correlated", "independent"):
        counted = [v for k, v in cells.items() if k[0] == bins and k[1] >= 6]
        assert len(counted) == 15
        cover = [1.0 - v[1] for v in counted]          # the printed cover is rounded
        holds.append(all(0.92 <= c <= 0.99 for c in cover))
        holds.append(not any(_lower(r, trials) > 0.05 for v in counted for r in v[1:3]))
    checks = re.findall(r"^check (\d) .*: (holds|FAILS)$", text, re.M)
    assert checks == [(str(i + 1), "holds" if h else "FAILS") for i, h in enumerate(holds)]
    return holds


def _profile_cells(name: str) -> dict:
    """(bins, runs of both arms, design, offset) -> the first rule's cover, wrong pass and
    wrong fail of a profiles_N.txt."""
    rows = [line.split() for line in (HERE / name).read_text().splitlines()
            if "|" in line and " vs " in line]
    return {(r[0], int(r[1]) + int(r[3]), r[1] + " vs " + r[3], float(r[4])):
            [float(v) for v in r[6:9]] for r in rows}


def test_smaller_upper_bound_run_is_what_the_readme_says():
    """profiles_3.txt (bench_coverage --profiles-3, registered before it): the registered
    command on its first line, the check lines recomputed from its cells (designs of >= 6
    runs, a rate shown above 0.05 by its lower 95 % Clopper-Pearson bound), the numbers the
    README quotes beside the fifth run's on the same designs, and the verdict's rule left
    unchanged because check 1 failed."""
    from ligwf.inference import equivalence as eq
    text, raw, registered = _registered_run("profiles_3.txt", r"nice -n 19 .*--profiles-3.*")
    assert "--trials 3000" in registered and "3000 studies a cell" in text
    assert raw.index("## Sixth run") < raw.index("### Sixth run's result")
    cells = _profile_cells("profiles_3.txt")
    assert len(cells) == 36
    assert _profile_checks(cells, text, 3000) == [False, True, True, True]
    assert "summary: 3 of 4 registered checks hold" in text
    result = " ".join(raw.split("### Sixth run's result", 1)[1].split())
    assert "**3 of 4 registered checks hold.**" in result
    corr = {k: v for k, v in cells.items() if k[0] == "correlated" and k[1] >= 6}
    above = sorted((k[2], k[3], 1.0 - v[1]) for k, v in corr.items() if 1.0 - v[1] > 0.99)
    assert above == [("24 vs 3", 0.0, 0.992), ("6 vs 6", 0.0, 0.991)]
    assert "6 vs 6 (0.991) and 24 vs 3 (0.992)" in result
    old = {k: v for k, v in _profile_cells("profiles_2.txt").items() if k in corr}
    assert [old[k][0] for k in sorted(corr) if k[3] == 0.0 and k[2] in ("6 vs 6", "24 vs 3")
            ] == [0.995, 0.997]                      # 6 vs 6, then 24 vs 3
    assert "The fifth run's bound gave 0.995 and 0.997 in those two cells" in result
    assert sum(1.0 - v[1] > 0.99 for v in old.values()) == 4 and len(above) == 2
    assert "go from 4 of 15 to 2 of 15" in result
    worst_pass = max(corr.items(), key=lambda kv: kv[1][1])
    assert worst_pass[0][2:] == ("24 vs 3", 3.0)
    assert f"Wrong pass at most {worst_pass[1][1]:.4f} (24 vs 3, offset 3" in result
    assert f"wrong fail at most {max(v[2] for v in corr.values()):.4f}" in result
    pooled = {k: (4000 * old[k][2] + 3000 * v[2]) / 7000 for k, v in corr.items()}
    worst = max(pooled, key=pooled.get)
    assert worst[2:] == ("6 vs 2", 1.0)
    assert f"wrong fail is at most {pooled[worst]:.4f} (6 vs 2, offset 1)" in result
    indep = [v for k, v in cells.items() if k[0] == "independent" and k[1] >= 6]
    assert (f"({min(1 - v[1] for v in indep):.3f}-{max(1 - v[1] for v in indep):.3f}; "
            "the fifth run's bound 0.955-0.979)") in result
    assert (f"{max(v[1] for v in indep):.4f} (pass) and {max(v[2] for v in indep):.4f} "
            "(fail)") in result
    guide = " ".join((ROOT / "docs" / "guide" / "analysis.md").read_text().split())
    cover = re.search(r"check 1 .*?\(([\d.]+-[\d.]+)\)", text).group(1)
    assert (f"a smaller bound simulated along the noise's largest direction covered {cover}, "
            "still above 0.99 at offset 0, and is not used: `profiles_3.txt`") in guide
    # check 1 failed: the verdict kept the fifth run's rule (the seventh run's since)
    assert eq.PROFILE_BINS != eq.BINS_SIMULATED_UPPER
    assert "stays the fifth run's" in result


def test_fiducial_upper_bound_run_is_what_the_readme_says():
    """profiles_4.txt (bench_coverage --profiles-4, registered before it): the registered
    command on its first line and its commit, the check lines recomputed from its cells
    (designs of >= 6 runs, a rate shown above 0.05 by its lower 95 % Clopper-Pearson bound),
    the numbers the README and the verdict's method sentence quote, and the verdict's rule
    switched to it because all four checks held."""
    from ligwf.inference import equivalence as eq
    text, raw, registered = _registered_run(
        "profiles_4.txt", r"OPENBLAS_NUM_THREADS=1 nice -n 19 .*--profiles-4.*")
    assert "--trials 3000 --seed 20261217" in registered and "3000 studies a cell" in text
    assert "registered in README.md before the run, commit b5648e7" in text.splitlines()[0]
    assert raw.index("## Seventh run") < raw.index("### Seventh run's result")
    cells = _profile_cells("profiles_4.txt")
    assert len(cells) == 36
    assert _profile_checks(cells, text, 3000) == [True, True, True, True]
    assert "summary: 4 of 4 registered checks hold" in text
    result = " ".join(raw.split("### Seventh run's result", 1)[1].split("\n## ", 1)[0].split())
    assert "**4 of 4 registered checks hold.**" in result
    corr = {k: v for k, v in cells.items() if k[0] == "correlated" and k[1] >= 6}
    indep = {k: v for k, v in cells.items() if k[0] == "independent" and k[1] >= 6}
    cover = sorted(1.0 - v[1] for v in corr.values())
    span = f"{cover[0]:.3f}-{cover[-1]:.3f}"
    assert f"({span})" in result and span == "0.955-0.972"
    at0 = {k[2]: 1.0 - v[1] for k, v in corr.items() if k[3] == 0.0}
    assert f"cover {at0['6 vs 6']:.3f} (6 vs 6;" in result
    assert f"and {at0['24 vs 3']:.3f} (24 vs 3;" in result
    worst_pass = max(corr.items(), key=lambda kv: kv[1][1])
    worst_fail = max(corr.items(), key=lambda kv: kv[1][2])
    assert (f"Wrong pass at most {worst_pass[1][1]:.4f} ({worst_pass[0][2]}, offset "
            f"{worst_pass[0][3]:.0f})") in result
    assert (f"wrong fail at most {worst_fail[1][2]:.4f} ({worst_fail[0][2]}, offset "
            f"{worst_fail[0][3]:.0f})") in result
    assert (f"({min(1 - v[1] for v in indep.values()):.3f}-"
            f"{max(1 - v[1] for v in indep.values()):.3f}; the sixth run's bound") in result
    assert f"At most {max(v[1] for v in indep.values()):.4f} (pass" in result
    assert f"and {max(v[2] for v in indep.values()):.4f} (fail)" in result
    # all four held and no committed table changed: the verdict's rule is this one
    assert eq.PROFILE_BINS == eq.BINS_SIMULATED_FIDUCIAL
    assert "`ligwf.inference.equivalence.PROFILE_BINS`" in result
    said = " ".join(eq.BINS_RULE_TEXT[eq.PROFILE_BINS].split())
    assert (f"covers {span} there and it errs at most {worst_pass[1][1]:.3f} (pass) and "
            f"{worst_fail[1][2]:.3f} (fail): docs/results/verdict_rates/profiles_4.txt") in said
    guide = " ".join((ROOT / "docs" / "guide" / "analysis.md").read_text().split())
    assert f"which covered {span} on correlated bins: `profiles_4.txt`" in guide
