"""Granule size distributions: binning and bootstrap (:mod:`.bins`), the GSD tables against
CG1 (:mod:`.tables`), replica pooling (:mod:`.pooling`), kinetics and the definition
sensitivity (:mod:`.kinetics`).
"""
