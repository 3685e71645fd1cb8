"""The frame loop's base class (ligwf.analysis.frames.loop): run() prepares once, analyses
the frames _prepare returns and concludes; frame() prepares once and hands out one frame's
result at a time, as the runner uses it; both analyses are its subclasses."""

from __future__ import annotations

from pathlib import Path

import pytest

from ligwf.analysis.flow.stage import FlowFrames
from ligwf.analysis.frames.dumps import FrameFiles
from ligwf.analysis.frames.loop import FrameAnalysis
from ligwf.analysis.granules.case import GranuleAnalysis


class EvenSteps(FrameAnalysis):
    """A toy analysis: the even steps only, each frame's step x 10."""

    def __init__(self):
        self.prepared = self.concluded = 0

    def _prepare(self, frames):
        self.prepared += 1
        return [ff for ff in super()._prepare(frames) if ff.step % 2 == 0]

    def _single_frame(self, ff):
        return ff.step * 10

    def _conclude(self):
        self.concluded += 1


def frames(*steps):
    return [FrameFiles(s, Path(f"p{s}.vtu"), None) for s in steps]


def test_run_owns_the_loop():
    a = EvenSteps().run(frames(1, 2, 3, 4))
    assert a.results == [20, 40] and (a.prepared, a.concluded) == (1, 1)


def test_frame_prepares_once_and_never_concludes():
    a = EvenSteps()
    assert [a.frame(ff) for ff in frames(2, 4, 6)] == [20, 40, 60]
    assert (a.prepared, a.concluded) == (1, 0)


def test_a_subclass_without_a_frame_method_says_so():
    with pytest.raises(NotImplementedError, match="analyses no frame"):
        FrameAnalysis().run(frames(2))


def test_both_analyses_are_frame_analyses():
    assert issubclass(GranuleAnalysis, FrameAnalysis) and issubclass(FlowFrames, FrameAnalysis)
