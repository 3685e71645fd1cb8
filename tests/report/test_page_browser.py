"""index.html in a real headless browser (Debian's Chromium): the report of a tiny real study
(CG1 and two Weber CG2 beside a cohesionless twin, real LIGGGHTS runs: the session's API
study of tests/apistudy.py, reported again here with snapshots into a folder of this test's
own) opens, shows the verdict first and the same sections as summary.md, and every figure
loads.

Chromium screenshots the page (checked to be a real picture, not a blank page) and dumps
the DOM after a small script, added to a copy of the page in the same folder (so relative
image paths still resolve), wrote each ``<img>``'s ``naturalWidth`` into a data attribute:
a missing or unreadable PNG has width 0. Without Chromium the test is skipped with the
reason; with ``CI=true`` it fails instead (the ``chromium`` fixture of tests/conftest.py).
"""

from __future__ import annotations

import os
import re
import subprocess
from html.parser import HTMLParser
from pathlib import Path

import numpy as np
import pytest

from apistudy import api_study
from ligwf.cli.main import main

pytestmark = [pytest.mark.browser, pytest.mark.engine, pytest.mark.mpi, pytest.mark.slow]

#: headless Chromium on a machine without network (see the machine notes: without the
#: background-networking flags it keeps trying to reach Google's hosts)
FLAGS = ["--headless", "--no-sandbox", "--disable-gpu", "--disable-quic", "--no-first-run",
         "--disable-background-networking", "--disable-component-update", "--disable-sync",
         "--hide-scrollbars", "--allow-file-access-from-files"]
PROBE = """<script>window.addEventListener("load", () => {
  for (const img of document.querySelectorAll("img")) img.dataset.naturalWidth = img.naturalWidth;
  document.body.dataset.checked = "1";
});</script>"""


@pytest.fixture(scope="module")
def report(engine, tmp_path_factory) -> Path:
    """The shared tiny study's report with its snapshots, in a folder of this test's own
    (the probe page written next to index.html never touches the shared study)."""
    study = api_study(engine, tmp_path_factory)
    out = tmp_path_factory.mktemp("page") / "report"
    assert main(["report", str(study), "--out", str(out)]) == 0
    return out


def run_chromium(chromium: str, profile: Path, *args: str) -> subprocess.CompletedProcess:
    profile.mkdir(parents=True, exist_ok=True)
    return subprocess.run([chromium, *FLAGS, f"--user-data-dir={profile}", *args],
                          capture_output=True, text=True, timeout=180,
                          env={**os.environ, "HOME": str(profile)})


class Page(HTMLParser):
    """The sections (id, title) and images (src, naturalWidth) of a dumped DOM."""

    def __init__(self):
        super().__init__()
        self.sections: list[str] = []
        self.titles: list[str] = []
        self.images: list[tuple[str, int | None]] = []
        self.checked = False
        self._in_h2 = False

    def handle_starttag(self, tag, attrs):
        a = dict(attrs)
        if tag == "section":
            self.sections.append(a.get("id", ""))
        elif tag == "h2":
            self._in_h2 = True
            self.titles.append("")
        elif tag == "img":
            w = a.get("data-natural-width")
            self.images.append((a.get("src", ""), int(w) if w is not None else None))
        elif tag == "body":
            self.checked = a.get("data-checked") == "1"

    def handle_endtag(self, tag):
        if tag == "h2":
            self._in_h2 = False

    def handle_data(self, data):
        if self._in_h2:
            self.titles[-1] += data


def test_the_page_shows_the_verdict_first_and_every_figure(chromium, report, tmp_path):
    page = report / "index.html"
    probe = report / "index.check.html"
    probe.write_text(page.read_text().replace("</body>", PROBE + "</body>"))
    shot = tmp_path / "page.png"
    done = run_chromium(chromium, tmp_path / "profile-shot", f"--screenshot={shot}",
                        "--window-size=1280,1600", page.as_uri())
    assert shot.is_file(), done.stderr[-2000:]
    from PIL import Image

    pixels = np.asarray(Image.open(shot).convert("L"), dtype=float)
    assert pixels.shape == (1600, 1280)
    assert pixels.std() > 10 and (pixels < 128).mean() > 0.005, "the screenshot is blank"

    dumped = run_chromium(chromium, tmp_path / "profile-dom", "--dump-dom",
                          "--virtual-time-budget=20000", probe.as_uri())
    dom = Page()
    dom.feed(dumped.stdout)
    assert dom.checked, "the page never finished loading: " + dumped.stderr[-2000:]
    assert dom.sections and dom.sections[0] == "verdict"
    assert dom.titles[0].startswith("Verdict")
    summary = (report / "summary.md").read_text()
    assert dom.titles == re.findall(r"^## (.*)$", summary, re.M)   # every section, in order
    pngs = sorted(p.name for p in (report / "figures").glob("*.png"))
    assert len(pngs) >= 6         # error vs run time, profiles, GSD, kinetics, snapshots
    assert sorted(Path(src).name for src, _ in dom.images) == pngs
    broken = [src for src, width in dom.images if not width]
    assert not broken, f"figures that did not render: {broken}"
    assert all(src.startswith("figures/") for src, _ in dom.images)   # relative, no network
