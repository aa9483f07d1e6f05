"""The renderer's per-pixel stage, compiled with numba: background, box spans, RGB packing.

Everything here is integer work on values numpy computed (rows, codes, fog weights), plus
the floor's raster lookup, whose floating-point operations per pixel are the same exactly
rounded IEEE operations, in the same order, as the numpy expression they replace (numba
without ``fastmath`` neither reorders them nor contracts them into FMAs). Pixels are painted
as shade-table entries (``R | G << 8 | B << 16``) into a ``uint32`` buffer, which is then
unpacked into the ``R, G, B`` bytes of the frame: no arithmetic touches a colour.

This module imports numba: :mod:`pytest_emrd.world._render` imports it on the first frame
only, so importing the package or collecting tests never loads numba. Compiled code is
cached on disk (``cache=True``: in ``__pycache__`` next to this file, else in the user's
cache directory); processes compiling at once each write their own file and rename it into
place, so concurrent xdist workers are safe.
"""

from __future__ import annotations

import numpy as np
from numba import njit

Walls = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
Floor = tuple[np.ndarray, np.ndarray, np.ndarray]
Rays = tuple[np.ndarray, np.ndarray, float, float, float]
Columns = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]


@njit(cache=True, nogil=True)
def compose(
    frame: np.ndarray,
    buf: np.ndarray,
    table: np.ndarray,
    ceiling: np.ndarray,
    walls: Walls,
    floor: Floor,
    rays: Rays,
    rects: np.ndarray,
    columns: Columns,
) -> None:
    """Paint the background, then the boxes, into ``buf`` and unpack it into ``frame``
    (``(S, S, 3)`` uint8). ``buf`` is uint32 scratch of ``S`` rows of at least ``S`` entries:
    rows padded by a cache line keep the column-wise box spans from evicting each other
    from the L1 cache (a 2 KiB row stride maps a whole column onto two cache sets).
    ``table`` maps codes to entries; see :func:`_background` and :func:`_boxes` for the other
    arguments."""
    _background(buf, table, ceiling, walls, floor, rays)
    _boxes(buf, table, rects, columns)
    size = frame.shape[1]
    for r in range(frame.shape[0]):
        row, out = buf[r], frame[r].reshape(-1)
        for c in range(size):
            entry = row[c]
            out[3 * c] = entry & 0xFF
            out[3 * c + 1] = (entry >> 8) & 0xFF
            out[3 * c + 2] = (entry >> 16) & 0xFF


@njit(cache=True, nogil=True)
def _background(
    buf: np.ndarray,
    table: np.ndarray,
    ceiling: np.ndarray,
    walls: Walls,
    floor: Floor,
    rays: Rays,
) -> None:
    """Ceiling, walls, skirting and floor everywhere.

    ``ceiling``: code of each of the upper ``H = len(ceiling)`` rows. ``walls``: per column
    the rows ``top <= H <= skirt <= bottom`` and the wall and skirting codes: rows
    ``[0, top)`` are ceiling, ``[top, skirt)`` wall, ``[skirt, bottom)`` skirting and
    ``[bottom, S)`` floor. ``floor``: ``(nz, nx)`` cell codes, the fog weight and the depth
    of each lower row. ``rays``: per column ``dx, dz``, the eye ``ox, oz`` and the raster's
    cells per metre: a floor pixel shows the cell of ``(o + depth * d) * scale``, clipped to
    the raster and truncated. (Constants come in as arguments: the on-disk cache would not
    notice a change to another module.)
    """
    top, skirt, bottom, wall, skirting = walls
    codes, fog, depth = floor
    dx, dz, ox, oz, scale = rays
    horizon = ceiling.shape[0]
    size, width = buf.shape[0], top.shape[0]
    nz, nx = codes.shape
    last_x, last_z = nx - 1.0, nz - 1.0
    for r in range(horizon):
        sky = table[ceiling[r]]
        for c in range(width):
            buf[r, c] = sky if r < top[c] else table[wall[c]]
    for r in range(horizon, size):
        d, f = depth[r - horizon], fog[r - horizon]
        for c in range(width):
            if r < skirt[c]:
                buf[r, c] = table[wall[c]]
            elif r < bottom[c]:
                buf[r, c] = table[skirting[c]]
            else:
                x = (d * dx[c] + ox) * scale
                z = (d * dz[c] + oz) * scale
                x = min(max(x, 0.0), last_x)
                z = min(max(z, 0.0), last_z)
                buf[r, c] = table[codes[int(z), int(x)] | f]


@njit(cache=True, nogil=True)
def _boxes(buf: np.ndarray, table: np.ndarray, rects: np.ndarray, columns: Columns) -> None:
    """Paint boxes in the order of ``rects``.

    ``rects`` rows ``r0, r1, c0, c1, at, two``: the box covers rows ``[r0, r1)`` of columns
    ``[c0, c1)``, its per-column entries start at ``at`` in ``columns`` = ``start, span,
    over, first, second``: rows ``[start, start + span)`` take code ``first``, then, when
    ``two``, rows ``[start, start + over)`` take code ``second`` (all within ``[r0, r1)``).
    """
    start, span, over, first, second = columns
    for b in range(rects.shape[0]):
        r0, r1, c0, c1, at, two = rects[b]
        for c in range(c0, c1):
            j = at + c - c0
            lo = max(np.int64(start[j]), r0)
            entry = table[first[j]]
            for r in range(lo, min(start[j] + np.int64(span[j]), r1)):
                buf[r, c] = entry
            if two:
                entry = table[second[j]]
                for r in range(lo, min(start[j] + np.int64(over[j]), r1)):
                    buf[r, c] = entry
