"""A fixed-size table from four float64 values (by bit pattern) to one float64, for
compiled kernels that meet the same arguments many times: the rupture work of touching
pairs of equal radii and bridge volume (:func:`ligwf.analysis.granules_numba.rupture_work`).

Open addressing with linear probing over :data:`SLOTS` slots; a kernel stops inserting
when it is half full (then new keys are simply computed), so a lookup always ends.
Keys compare by bits, so a value found is the value the kernel computed for exactly
these arguments (bit-identical reuse)."""

from __future__ import annotations

import numpy as np

from ligwf.numba_cache import cached_jit

#: slots of a table (a power of two)
SLOTS = 1 << 16


@cached_jit()
def new_table():
    """(keys, values, used, [filled]) of an empty table."""
    return (np.empty((SLOTS, 4), np.int64), np.empty(SLOTS, np.float64),
            np.zeros(SLOTS, np.bool_), np.zeros(1, np.int64))


@cached_jit(inline="always")
def find_slot(table, bits, k):
    """The slot of key ``k`` (the four int64 bit-pattern arrays ``bits`` at row ``k``):
    ``table[2][slot]`` (used) tells whether it holds the key, else the key may go there;
    -1 when the key is absent and the table half full (compute, do not remember)."""
    keys, used = table[0], table[2]
    a, b, c, d = bits[0][k], bits[1][k], bits[2][k], bits[3][k]
    h = a * 0x9E3779B1 + b * 0x85EBCA77 + c * 0xC2B2AE3D + d * 0x27D4EB2F
    slot = (h ^ (h >> 29)) & (SLOTS - 1)
    while used[slot] and not (keys[slot, 0] == a and keys[slot, 1] == b
                              and keys[slot, 2] == c and keys[slot, 3] == d):
        slot = (slot + 1) & (SLOTS - 1)
    if not used[slot] and 2 * table[3][0] >= SLOTS:
        return -1
    return slot


@cached_jit(inline="always")
def remember(table, bits, k, slot, value):
    """Store ``value`` for key ``k`` in the free ``slot`` :func:`find_slot` gave."""
    for col in range(4):
        table[0][slot, col] = bits[col][k]
    table[1][slot] = value
    table[2][slot] = True
    table[3][0] += 1
