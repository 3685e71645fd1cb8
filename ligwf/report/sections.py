"""The report as an ordered list of sections, rendered to ``summary.md`` and ``index.html``.

A :class:`Section` is a title, an anchor (the HTML id and the table of contents link), a
markdown body and optionally an HTML body (empty: :mod:`ligwf.report.html` renders the
markdown). Both files show the same list in the same order, so nothing the markdown says
is missing from the page. Modules that build a section return markdown that starts with
``## Title`` (the house style of every report module); :func:`split_markdown` cuts such
text into sections, one per ``##`` heading.

The order (:data:`SECTION_ORDER`) puts the answer first: the verdict, then the tables it
rests on, the controls and the granule results, the figures, and last what the report
left out and where to look further (stability, ParaView).
"""

from __future__ import annotations

import re
from dataclasses import dataclass
from pathlib import Path
from typing import Iterable

#: the report's sections by anchor, in reading order (a section without an entry goes last)
SECTION_ORDER = ("verdict", "extrapolated-cg1", "rounds", "cases", "conditions", "cg1-noise-floor", "size-limit",
                 "steady-window", "resolution-and-grains", "liquid-spreading", "granule-controls", "gsd", "kinetics", "flow-fields",
                 "skipped-cases", "skipped-or-missing-frames", "analysis-outputs", "granules",
                 "figures", "snapshots", "stability", "paraview")

#: anchors of sections whose title does not slug to their anchor
ANCHORS = {"Conditions (value [95 % interval])": "conditions",
           "Skipped cases (not used anywhere in this report)": "skipped-cases",
           "GSD size limit and replica pooling": "size-limit",
           "Granule controls (wet bed / cohesionless twin)": "granule-controls",
           "Granulation kinetics": "kinetics"}


@dataclass(frozen=True)
class Section:
    """One section of the report: what summary.md and index.html both show."""

    title: str
    anchor: str
    markdown: str        # body below the heading (markdown, no ``## title`` line)
    html: str = ""       # body as HTML; empty: rendered from ``markdown``

    def as_markdown(self) -> str:
        """``## title`` and the body, as summary.md shows it."""
        return f"## {self.title}\n\n{self.markdown.strip()}\n"


@dataclass(frozen=True)
class Figure:
    """One figure of the report: its caption and the PNG (under the report's figures/)."""

    title: str
    path: Path


def slug(title: str) -> str:
    """The anchor of a title: :data:`ANCHORS`, else lower-case words joined by '-'."""
    if title in ANCHORS:
        return ANCHORS[title]
    return re.sub(r"[^a-z0-9]+", "-", title.lower()).strip("-") or "section"


def split_markdown(text: str | Iterable[str]) -> list[Section]:
    """Sections of markdown text, one per ``## `` heading (text before the first heading
    is dropped: a section module's text starts with its heading)."""
    lines = text.splitlines() if isinstance(text, str) else list(text)
    out: list[tuple[str, list[str]]] = []
    for line in lines:
        if line.startswith("## "):
            out.append((line[3:].strip(), []))
        elif out:
            out[-1][1].append(line)
    return [Section(t, slug(t), "\n".join(body).strip()) for t, body in out]


def ordered(sections: Iterable[Section]) -> list[Section]:
    """Sections in :data:`SECTION_ORDER` (stable: sections of one anchor keep their
    order; an anchor not listed goes after the listed ones)."""
    rank = {a: i for i, a in enumerate(SECTION_ORDER)}
    items = list(sections)
    return sorted(items, key=lambda s: rank.get(s.anchor, len(rank)))


def figure_markdown(figures: Iterable[Figure], figures_dir: str) -> str:
    """Markdown image lines of figures (relative paths, so the folder can be moved)."""
    return "\n\n".join(f"![{f.title}]({figures_dir}/{f.path.name})" for f in figures)


def figure_section(title: str, anchor: str, intro: str, figures: list[Figure],
                   figures_dir: str) -> Section:
    """A section of an introductory paragraph and figures (markdown images; the page
    shows them inline with their captions)."""
    body = "\n\n".join(p for p in (intro, figure_markdown(figures, figures_dir)) if p)
    return Section(title, anchor, body or "none")


def render_markdown(title: str, preamble: str, sections: Iterable[Section]) -> str:
    """summary.md: ``# title``, the preamble, every section in order (the page adds the
    table of contents; markdown viewers slug headings each their own way)."""
    parts = [f"# {title}", "", preamble.strip(), ""] + [s.as_markdown() for s in sections]
    return "\n".join(parts)
