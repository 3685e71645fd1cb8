"""Flow metrics: per frame (:mod:`.frame`, the surface fit :mod:`.surface`), the metric
registry (:mod:`.registry`), the steady window (:mod:`.steady`) and the flow stage of a
study (:mod:`.stage`).
"""
