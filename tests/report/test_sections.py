"""The report's section structure: summary.md and index.html show the same sections in the
same order, the verdict first; wide tables fold, markup in the text is escaped."""

from __future__ import annotations

import re
from pathlib import Path

from ligwf.report.html import WIDE_COLUMNS, markdown_html, render_page
from ligwf.report.sections import (Figure, Section, figure_section, ordered, render_markdown,
                                   split_markdown)

TEXT = """## Cases

| a | b |
|---|---|
| 1 | 2 |

## CG1 noise floor

floor text

## Conditions (value [95 % interval])

cond text
"""


def test_split_markdown_cuts_at_headings_and_names_anchors():
    parts = split_markdown(TEXT)
    assert [(s.title, s.anchor) for s in parts] == [
        ("Cases", "cases"), ("CG1 noise floor", "cg1-noise-floor"),
        ("Conditions (value [95 % interval])", "conditions")]
    assert parts[1].markdown == "floor text"


def test_ordered_puts_the_verdict_first_and_keeps_the_reading_order():
    parts = ordered([*split_markdown(TEXT), Section("ParaView", "paraview", "x"),
                     Section("Verdict", "verdict", "pass"), Section("Other", "other", "y")])
    assert [s.anchor for s in parts] == ["verdict", "cases", "conditions", "cg1-noise-floor",
                                         "paraview", "other"]


def test_markdown_and_page_show_the_same_sections_in_the_same_order():
    parts = ordered([*split_markdown(TEXT), Section("Verdict", "verdict", "**CG2** passes")])
    md = render_markdown("study", "intro", parts)
    page = render_page("study", "intro", parts)
    md_titles = re.findall(r"^## (.*)$", md, re.M)
    page_titles = re.findall(r"<h2>(.*?)</h2>", page)
    assert md_titles == [s.title for s in parts]
    assert [t.replace("&amp;", "&") for t in page_titles] == md_titles
    assert re.findall(r'<section id="([^"]+)"', page)[0] == "verdict"
    assert "<strong>CG2</strong> passes" in page
    assert page.count('<a href="#') == len(parts)        # the table of contents
    assert "http" not in page.split("<body>")[1]          # self-contained: no network


def test_wide_tables_fold_and_narrow_ones_do_not():
    wide = WIDE_COLUMNS + 1
    text = ("| " + " | ".join(f"c{i}" for i in range(wide)) + " |\n" + "|---" * wide + "|\n"
            + "| " + " | ".join("1" for _ in range(wide)) + " |\n")
    out = markdown_html(text)
    assert out.startswith("<details open><summary>table of 1 row(s) and") and "<table>" in out
    many = text + ("| " + " | ".join("2" for _ in range(wide)) + " |\n") * 20
    assert markdown_html(many).startswith("<details><summary>table of 21 row(s)")
    narrow = markdown_html("| a | b |\n|---|---|\n| 1 | 2 |\n")
    assert "<details>" not in narrow and 'class="scroll"' in narrow


def test_markup_in_text_is_escaped():
    out = markdown_html("case <script>alert(1)</script> | `x`")
    assert "<script>" not in out and "&lt;script&gt;" in out


def test_figures_are_inline_with_captions():
    sec = figure_section("Figures", "figures", "intro", [Figure("GSD overlay", Path("/x/g.png"))],
                         "figures")
    assert "![GSD overlay](figures/g.png)" in sec.markdown
    out = markdown_html(sec.markdown)
    assert '<figure><a href="figures/g.png"><img src="figures/g.png" alt="GSD overlay"></a>' in out
    assert "<figcaption>GSD overlay</figcaption>" in out
