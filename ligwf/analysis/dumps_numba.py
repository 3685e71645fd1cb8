"""Compiled (numba) helpers of the dump reader: base64 decoding and duplicate-pair search.

Why compiled: a 360k-particle contact dump holds ~900k rows; CPython's base64 decoder and
numpy's sort-based ``unique`` then take most of the time of reading a frame. Both helpers
here are single passes. Each declines (returns a failure code) on input it does not handle
exactly (whitespace or padding inside the base64, ids too large for a lookup table), and
the caller falls back to the standard library / numpy path, so results never differ.
"""

from __future__ import annotations

import numpy as np

from ligwf.numba_cache import cached_jit
_ALPHABET = b"ABCDEFGHIJKLMNOPQRSTUVWXYZabcdefghijklmnopqrstuvwxyz0123456789+/"
_TABLE = np.full(256, -1, np.int16)
_TABLE[np.frombuffer(_ALPHABET, np.uint8)] = np.arange(64)


@cached_jit()
def _decode(text, table, out, pad):
    n = len(text)
    while n > 0 and text[n - 1] == 61:          # trailing '=' padding
        n -= 1
    if len(text) - n > 2 or (len(text) % 4 != 0):
        return -1
    o = pad
    full = n // 4 * 4
    for k in range(0, full, 4):
        a, b, c, d = table[text[k]], table[text[k + 1]], table[text[k + 2]], table[text[k + 3]]
        if a < 0 or b < 0 or c < 0 or d < 0:
            return -1
        word = (a << 18) | (b << 12) | (c << 6) | d
        out[o] = (word >> 16) & 255
        out[o + 1] = (word >> 8) & 255
        out[o + 2] = word & 255
        o += 3
    rest = n - full
    if rest == 1:
        return -1
    if rest >= 2:
        a, b = table[text[full]], table[text[full + 1]]
        c = table[text[full + 2]] if rest == 3 else 0
        if a < 0 or b < 0 or c < 0:
            return -1
        word = (a << 18) | (b << 12) | (c << 6)
        out[o] = (word >> 16) & 255
        o += 1
        if rest == 3:
            out[o] = (word >> 8) & 255
            o += 1
    return o


def decode_base64(text: bytes, header_size: int) -> np.ndarray | None:
    """Strict base64 decode of one block whose first ``header_size`` bytes are a header.

    Returns the decoded bytes (header included) in a buffer where the bytes after the
    header start 8-byte aligned, so they can be viewed as float64 without a copy; None if
    the text is not plain padded base64 (the caller then uses binascii, which also skips
    stray characters, and reports the size mismatch that follows).
    """
    pad = (8 - header_size % 8) % 8
    size = pad + len(text) * 3 // 4
    out = np.empty(size // 8 + 1, np.float64).view(np.uint8)   # 8-byte aligned start
    end = _decode(np.frombuffer(text, np.uint8), _TABLE, out, pad)
    if end < 0:
        return None
    return out[pad:end]


@cached_jit()
def _first_of_each_pair(lo, hi, max_id):
    m = len(lo)
    start = np.zeros(max_id + 2, np.int64)
    for k in range(m):
        start[lo[k] + 1] += 1
    for v in range(max_id + 1):
        start[v + 1] += start[v]
    order = np.empty(m, np.int64)
    fill = start[:-1].copy()
    for k in range(m):                       # contacts bucketed by lo, in row order
        order[fill[lo[k]]] = k
        fill[lo[k]] += 1
    mark = np.full(max_id + 1, -1, np.int64)
    keep = np.ones(m, np.bool_)
    duplicates = 0
    for v in range(max_id + 1):
        for p in range(start[v], start[v + 1]):
            k = order[p]
            if mark[hi[k]] == v:
                keep[k] = False
                duplicates += 1
            else:
                mark[hi[k]] = v
    return duplicates, keep


def first_of_each_pair(lo: np.ndarray, hi: np.ndarray) -> np.ndarray | None:
    """Row indices (ascending) of the first listing of each (lo, hi) pair, or None when
    every pair is listed once. O(rows + largest id) instead of a sort."""
    if len(lo) == 0:
        return None
    max_id = int(max(lo.max(), hi.max()))
    if max_id > 8 * len(lo) + 1_000_000:     # sparse huge ids: a table would waste memory
        key = lo * (max_id + 1) + hi
        first = np.unique(key, return_index=True)[1]
        return None if len(first) == len(lo) else np.sort(first)
    duplicates, keep = _first_of_each_pair(lo, hi, max_id)
    return None if duplicates == 0 else np.flatnonzero(keep)


def warm_up() -> None:
    """Compile (or load from the cache) both helpers on tiny inputs."""
    decode_base64(b"AQAAAAI=", 4)
    first_of_each_pair(np.array([1, 1]), np.array([2, 2]))
