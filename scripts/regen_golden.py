#!/usr/bin/env python3
"""Regenerate the golden LIGGGHTS inputs listed in tests/golden/cases.yaml.

Run after an intended template or scaling change, then review `git diff tests/golden`.
"""

from __future__ import annotations

import sys
from pathlib import Path

import yaml

ROOT = Path(__file__).resolve().parent.parent
sys.path.insert(0, str(ROOT))

from ligwf.engine.render import render  # noqa: E402
from ligwf.scene.workflow import load_workflow  # noqa: E402

GOLDEN = ROOT / "tests" / "golden"


def golden_cases() -> list[dict]:
    return yaml.safe_load((GOLDEN / "cases.yaml").read_text())


def render_golden(entry: dict) -> str:
    wf = load_workflow(ROOT / entry["workflow"], entry.get("set", []))
    case = next(c for c in wf.cases if c.case_id == entry["case"])
    return render(case.scaled())["in.liggghts"]


def main() -> int:
    for entry in golden_cases():
        path = GOLDEN / f"{entry['name']}.in"
        path.write_text(render_golden(entry))
        print(f"wrote {path.relative_to(ROOT)}")
    return 0


if __name__ == "__main__":
    sys.exit(main())
