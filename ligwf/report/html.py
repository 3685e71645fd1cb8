"""index.html: the report's sections as one self-contained page.

The page shows exactly the sections of summary.md (:mod:`ligwf.report.sections`), in the
same order, the verdict first, with a table of contents. Section bodies are the markdown
rendered by markdown-it (CommonMark + tables, raw HTML off: a case id or a reason can never
inject markup); a section may bring its own HTML instead. Tables wider than
:data:`WIDE_COLUMNS` fold into a ``<details>`` element (open up to :data:`OPEN_ROWS`
rows), every table scrolls sideways on its own instead of widening the page, and figures
are inline ``<figure>`` elements with their captions (a click opens the PNG at full
size; snapshots two a row). No network: the CSS is inline and
the images are relative paths into the report folder, so the folder can be moved or
zipped.
"""

from __future__ import annotations

import html
import re
from typing import Iterable

from markdown_it import MarkdownIt

from ligwf.report.sections import Section

#: tables with more columns than this fold into a <details> element ...
WIDE_COLUMNS = 8
#: ... shown open when it has at most this many rows (a short table is read, not hunted)
OPEN_ROWS = 8

_MD = MarkdownIt("commonmark", {"html": False}).enable("table")
_TABLE = re.compile(r"<table>.*?</table>", re.S)
_FIGURE = re.compile(r'<p><img src="([^"]*)" alt="([^"]*)" ?/?></p>')

CSS = """
body{font-family:system-ui,-apple-system,"Segoe UI",Roboto,sans-serif;margin:0;color:#1d1d1f;
 background:#fafafa;line-height:1.45}
main{max-width:1100px;margin:0 auto;padding:1.5em 2em 4em;background:#fff}
h1{font-size:1.6em;margin:.4em 0}h2{font-size:1.25em;margin-top:1.8em;
 border-bottom:1px solid #ddd;padding-bottom:.2em}
nav{font-size:.9em;background:#f3f5f8;border:1px solid #e0e4ea;border-radius:6px;
 padding:.6em 1em;margin:1em 0}
nav ol{margin:.2em 0;padding-left:1.4em;columns:2}nav a{text-decoration:none}
section#verdict{background:#f4f9f4;border:1px solid #cfe3cf;border-radius:6px;
 padding:0 1em .8em}
.scroll{overflow-x:auto;max-width:100%;margin:.6em 0}
table{border-collapse:collapse;font-size:13px}
th{background:#f0f2f5;text-align:left;vertical-align:bottom}
td,th{padding:3px 8px;border-bottom:1px solid #e3e3e3;white-space:nowrap}
tr:nth-child(even) td{background:#fafbfc}
details{margin:.6em 0}summary{cursor:pointer;color:#245;font-size:.95em}
figure{margin:1em 0}figure img{max-width:100%;height:auto;border:1px solid #eee}
figcaption{font-size:.9em;color:#555}
section#snapshots figure{display:inline-block;vertical-align:top;width:47%;margin:.5em 1%}
code{background:#f3f3f3;padding:0 .2em;border-radius:3px}
"""


def _fold(match: re.Match) -> str:
    """A table in a sideways-scrolling box; a wide one folded into <details>."""
    table = match.group(0)
    head = table.split("</thead>", 1)[0]
    columns, rows = head.count("<th"), table.count("<tr") - 1
    box = f'<div class="scroll">{table}</div>'
    if columns <= WIDE_COLUMNS:
        return box
    state = " open" if rows <= OPEN_ROWS else ""
    return (f"<details{state}><summary>table of {rows} row(s) and {columns} columns "
            f"(click to fold or unfold)</summary>{box}</details>")


def markdown_html(text: str) -> str:
    """HTML of a section's markdown: tables boxed (wide ones folded), images as figures."""
    out = _MD.render(text)
    out = _TABLE.sub(_fold, out)
    return _FIGURE.sub(lambda m: f'<figure><a href="{m.group(1)}"><img src="{m.group(1)}" '
                                 f'alt="{m.group(2)}"></a>'
                                 f"<figcaption>{m.group(2)}</figcaption></figure>", out)


def section_html(section: Section) -> str:
    """One ``<section>`` with its heading and body."""
    body = section.html or markdown_html(section.markdown)
    return (f'<section id="{html.escape(section.anchor)}">'
            f"<h2>{html.escape(section.title)}</h2>\n{body}</section>")


def render_page(title: str, preamble: str, sections: Iterable[Section]) -> str:
    """The whole page: title, preamble, contents, every section in order."""
    sections = list(sections)
    toc = "".join(f'<li><a href="#{html.escape(s.anchor)}">{html.escape(s.title)}</a></li>'
                  for s in sections)
    body = "\n".join(section_html(s) for s in sections)
    return (f'<!doctype html>\n<html lang="en"><head><meta charset="utf-8">'
            f'<meta name="viewport" content="width=device-width, initial-scale=1">'
            f"<title>{html.escape(title)}</title><style>{CSS}</style></head><body><main>\n"
            f"<h1>{html.escape(title)}</h1>\n{markdown_html(preamble)}\n"
            f'<nav aria-label="contents"><b>Contents</b><ol>{toc}</ol></nav>\n'
            f"{body}\n</main></body></html>\n")
