"""Granule size distributions: binning and bootstrap (:mod:`.bins`), the GSD tables against
CG1 (:mod:`.tables`), replica pooling (:mod:`.pooling`), bin-free distances of CG samples
against the CG1 noise floor (:mod:`.sample_distances`), kinetics and the definition
sensitivity (:mod:`.kinetics`), definitions compared case by case (:mod:`.definition_cases`).
"""
