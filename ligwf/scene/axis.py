"""The drum axis: one value from the workflow (``drum.axis: y``) to the kernels.

A position's columns are x, y, z; an :class:`Axis` knows its column (:attr:`Axis.index`)
and the drum frame around it (:attr:`Axis.frame`: the axial, across and vertical columns,
gravity along -vertical). Records and workflows keep the letter (``"y"``).
"""

from __future__ import annotations

from enum import Enum


class Axis(str, Enum):
    """A Cartesian axis, spelled as its letter (the drum's rotation axis, a periodic axis)."""

    X = "x"
    Y = "y"
    Z = "z"

    def __str__(self) -> str:               # the letter, also where str() is taken (3.10)
        return self.value

    def __format__(self, spec: str) -> str:
        return format(self.value, spec)

    @property
    def index(self) -> int:
        """Column of this axis in a position (x 0, y 1, z 2)."""
        return "xyz".index(self.value)

    @property
    def frame(self) -> tuple[int, int, int]:
        """Columns (axial, across, vertical) of the drum frame about this axis: vertical is
        'up' (gravity along -vertical), across the remaining horizontal column."""
        return _FRAMES[self]


_FRAMES = {Axis.X: (0, 1, 2), Axis.Y: (1, 0, 2), Axis.Z: (2, 0, 1)}
