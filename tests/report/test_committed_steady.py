"""docs/results/steady: the README's numbers are those of the committed bench_steady.txt."""

from __future__ import annotations

import re

from tests.helpers import ROOT

HERE = ROOT / "docs" / "results" / "steady"


def _rows() -> list[dict]:
    lines = (HERE / "bench_steady.txt").read_text().splitlines()
    assert lines[0].startswith("# ") and "bench_steady" in lines[0]
    rows = []
    for line in lines:
        m = re.match(r"^\s*(\d+)\s+([\d.]+)\s+([\d.]+)\s+(yes|no) \|\s+([\d.]+)\s+[\d.]+\s+"
                     r"(-?[\d.]+) \|\s+([\d.]+)\s+[\d.]+\s+(-?[\d.]+)$", line)
        if m:
            rows.append({"frames": int(m.group(1)), "startup": m.group(4) == "yes",
                         "current": float(m.group(5)), "current_bias": float(m.group(6)),
                         "mser": float(m.group(7)), "mser_bias": float(m.group(8))})
    assert len(rows) == 24
    return rows


def test_readme_numbers_are_the_benchmark():
    rows = _rows()
    text = " ".join((HERE / "README.md").read_text().split())
    still = [r for r in rows if not r["startup"]]

    def span(key, frames):
        sub = [r[key] for r in still if r["frames"] == frames]
        return f"{min(sub):.2f}-{max(sub):.2f}"

    assert (f"in {span('current', 40)} of runs at 40 frames, {span('current', 80)} at 80 and "
            f"{span('current', 160)} at 160") in text
    assert (f"MSER-5 caps {span('mser', 40)} of runs at 40 frames, {span('mser', 80)} at 80 "
            f"and {span('mser', 160)} at 160") in text
    bias = max(max(abs(r["current_bias"]), abs(r["mser_bias"])) for r in rows)
    assert f"at most {bias:.2f} standard errors" in text
    # the hypotheses as the file states them, and growth with length in every cell
    verdicts = (HERE / "bench_steady.txt").read_text()
    for h in ("H1", "H2"):
        assert re.search(rf"^{h} .*: does not hold$", verdicts, re.M)
        assert f"**{h} does not hold**" in text
    for i in range(0, len(rows), 3):
        cell = rows[i:i + 3]
        if not cell[0]["startup"]:
            assert [r["frames"] for r in cell] == [40, 80, 160]
            assert cell[2]["current"] > cell[0]["current"]
    low = [r["current"] for r in still if r["frames"] == 160 and r["current"] < 0.25]
    assert len(low) == 1 and f"caps {low[0]:.2f} at 160 frames" in text
