"""Long warnings are wrapped to the terminal's width at spaces, with a hanging indent, and
stay one line in a log or pipe (issue 33: `ligwf check` on a 60 mm drum printed warnings cut
by the terminal)."""

from __future__ import annotations

import io

from rich.console import Console

from ligwf.cli.common import WARNING_PREFIX, print_warning, wrapped_warning

LONG = ("cg1-none-r0, cg1-none-r1, cg1-none-r2: analysis.hold_time = 0.5 s is shorter than "
        "1.25x the co-rotating plug residence of this drum (0.8 s): held granules would be "
        "fragments of the plug; use at least 1.0 s (see 'ligwf check')")


def test_a_long_warning_is_broken_at_spaces_within_the_width():
    lines = wrapped_warning(LONG, 60)
    assert len(lines) > 2
    assert lines[0].startswith(WARNING_PREFIX)
    assert all(len(line) <= 60 for line in lines)
    assert all(line.startswith("  ") for line in lines[1:])
    # nothing lost or cut mid-word: the words read back are the warning's words
    words = " ".join(lines)[len(WARNING_PREFIX):].split()
    assert words == LONG.split()


def test_no_terminal_keeps_the_warning_on_one_line():
    assert wrapped_warning(LONG, None) == [WARNING_PREFIX + LONG]
    assert wrapped_warning("short", 100) == [WARNING_PREFIX + "short"]


def test_a_word_longer_than_the_width_is_kept_whole():
    path = "/very/long/" + "x" * 80 + "/study"
    lines = wrapped_warning(f"cannot write {path}", 50)
    assert path in lines[1]


def test_print_wraps_on_a_terminal_and_not_in_a_pipe():
    buf = io.StringIO()
    term = Console(file=buf, width=70, force_terminal=True, color_system=None, soft_wrap=True)
    print_warning(LONG, term)
    shown = buf.getvalue().splitlines()
    assert len(shown) == len(wrapped_warning(LONG, 70)) and all(len(s) <= 70 for s in shown)
    assert shown[0].startswith("ligwf: warning: cg1-none-r0")
    buf = io.StringIO()
    pipe = Console(file=buf, width=70, force_terminal=False, soft_wrap=True)
    print_warning(LONG, pipe)
    assert buf.getvalue() == WARNING_PREFIX + LONG + "\n"
