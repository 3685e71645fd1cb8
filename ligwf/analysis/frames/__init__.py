"""Frames: the engine's VTK dumps read fast (:mod:`.vtu`), turned into frames (:mod:`.dumps`),
and checked against the run that wrote them (:mod:`.checks`).
"""
