"""The sequential procedure under the verdict's rules (docs/results/verdict_rates, its
section registered before the run): every number of the README's result is read from the
committed ``sequential.txt``, and the file's check line is recomputed from its own cells."""

from __future__ import annotations

import re
from pathlib import Path

from benchmarks.verdict_designs import lower_bound

HERE = Path(__file__).resolve().parents[2] / "docs" / "results" / "verdict_rates"
TRIALS = 2000       # registered: 2,000 null studies a cell


def _cells() -> tuple[list[dict], str]:
    text = (HERE / "sequential.txt").read_text()
    first = text.splitlines()[0]
    assert first.startswith("# ") and ("--sequential-only --sequential-trials 2000 "
                                       "--fail-sides 2 --seed 20261213") in first
    cells = []
    for line in text.splitlines():
        m = re.match(r"^\s*(\d)\s+(\d+)\s+([\d.]+)\s+([\d.]+) \|\s+([\d.]+)\s+([\d.]+) \|\s+"
                     r"([\d.]+)$", line)
        if m:
            cells.append({"R": int(m.group(1)), "frames": int(m.group(2)),
                          "phi": float(m.group(3)), "offset": float(m.group(4)),
                          "pass": float(m.group(5)), "fail": float(m.group(6)),
                          "decided": m.group(7)})
    return cells, text


def test_the_sequential_check_is_its_cells_and_the_readme_says_them():
    cells, text = _cells()
    assert len(cells) == 16 and "two-sided fail test" in text
    assert {(c["R"], c["frames"], c["phi"], c["offset"]) for c in cells} == {
        (r, f, p, o) for r in (2, 3) for f in (20, 100) for p in (0.3, 0.8) for o in (0.0, 1.0)}
    # the cells are printed to 3 decimals (a count of 2,000 to +-1), so the bound recomputed
    # from them is the file's to within a count's worth
    recomputed = max(lower_bound(max(c["pass"], c["fail"]), TRIALS) for c in cells)
    m = re.search(r"^check sequential .*: (holds|FAILS) \(largest lower 95 % bound "
                  r"([\d.]+)\)$", text, re.M)
    shown, holds = float(m.group(2)), m.group(1) == "holds"
    assert abs(shown - recomputed) < 1e-3 and holds == (shown <= 0.05) == (recomputed <= 0.05)
    readme = " ".join((HERE / "README.md").read_text().split())
    section = readme[readme.index("### The sequential procedure's result"):]
    assert f"**The registered check {'holds' if holds else 'fails'}.**" in section
    assert (f"wrong pass in at most {max(c['pass'] for c in cells):.3f} and a wrong fail in at "
            f"most {max(c['fail'] for c in cells):.3f} of null studies (largest lower 95 % "
            f"bound {shown:.4f})") in section

    def span(offset):
        values = sorted(float(c["decided"]) for c in cells if c["offset"] == offset)
        return f"{values[0]:.3f}-{values[-1]:.3f}"

    assert f"decides {span(0.0)} of the studies whose truth is 0" in section
    assert f"with an offset of 1 frame sd, {span(1.0)}" in section
