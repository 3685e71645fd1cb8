"""ligwf: coarse-grained LIGGGHTS studies of wet granulation in rotating drums.

The pipeline, one module per stage:
scene -> scaling -> mesh -> render -> (launch) -> dumps -> granules -> gsd/flow -> report.
"""

__version__ = "0.1.0"
