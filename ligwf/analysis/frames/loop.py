"""The frame loop every per-frame analysis shares (the life cycle of MDAnalysis'
``analysis/base.py``).

A subclass of :class:`FrameAnalysis` writes ``_single_frame`` (one frame's result) and may
write ``_prepare`` (once, before the frames: it sets up what every frame needs and returns
the frames to analyse) and ``_conclude`` (once, after them). :meth:`FrameAnalysis.run` owns
the loop over a list of frames and fills ``results``; :meth:`FrameAnalysis.frame` hands out
one frame's result at a time, the analysis prepared on the first call, for callers that
share frames out themselves (the MPI ranks and array tasks of
:mod:`ligwf.analysis.runner`). The granule analysis
(:class:`~ligwf.analysis.granules.case.GranuleAnalysis`) and the flow metrics' frame pass
(:class:`~ligwf.analysis.flow.stage.FlowFrames`) are its subclasses.
"""

from __future__ import annotations

from typing import Any, Sequence

from ligwf.analysis.frames.dumps import FrameFiles


class FrameAnalysis:
    """Base of the per-frame analyses (module docstring); ``results`` holds what
    ``_single_frame`` returned, frame by frame, after :meth:`run`."""

    results: list

    def run(self, frames: Sequence[FrameFiles] | None = None) -> "FrameAnalysis":
        """Prepare, analyse every frame ``_prepare`` returns (from ``frames``), conclude."""
        todo = self._prepare(frames)
        self._ready = True
        for ff in todo:
            self.results.append(self._single_frame(ff))
        self._conclude()
        return self

    def frame(self, ff: FrameFiles) -> Any:
        """One frame's result (the analysis prepared on the first call, never concluded:
        the caller gathers the results)."""
        if not getattr(self, "_ready", False):
            self._prepare([ff])
            self._ready = True
        return self._single_frame(ff)

    def _prepare(self, frames: Sequence[FrameFiles] | None) -> list[FrameFiles]:
        self.results = []
        return list(frames or ())

    def _single_frame(self, ff: FrameFiles) -> Any:
        raise NotImplementedError(f"{type(self).__name__} analyses no frame")

    def _conclude(self) -> None:
        """After the frames (nothing by default)."""
