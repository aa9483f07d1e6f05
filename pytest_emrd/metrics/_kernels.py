"""Compiled loops of the matcher (:mod:`._align`), bitwise equal to the numpy they replace.

Imported on first use only (numba's import and its cached machine code cost a few hundred
milliseconds that ``import pytest_emrd.metrics`` must not pay). Each kernel does, on the few
entries and objects of one map, exactly the float operations numpy did on arrays, in
numpy's order, so every result has the same bits (oracles: ``tests/metrics/test_align.py``):

* no reassociation and no fused multiply-add where numpy has none (numba compiles without
  fast-math, so LLVM contracts nothing), and an explicit fused multiply-add where numpy has
  one: ``points @ R`` of two or more rows runs OpenBLAS's ``dgemm``, whose kernel computes
  ``x * R[0, j]`` and adds ``z * R[1, j]`` to it in one rounding (:func:`_turn`); a single
  row goes through numpy's own loop, without it;
* sums of many terms in numpy's pairwise order (:func:`_pairwise`, as
  :func:`._align.numpy_sum`);
* rounding as ``np.round``: scale by ``10**decimals``, round half to even, scale back.
"""

from __future__ import annotations

import math

import numba
import numpy as np
from numba.core import types
from numba.extending import intrinsic

from pytest_emrd.metrics._align import Objects

# Numba compiles these on first use and keeps the machine code beside this file
# (``cache=True``): later processes load it instead of compiling.
_jit = numba.njit(cache=True, nogil=True)


@intrinsic
def _fma(typingctx, a, b, c):
    """``a * b + c`` rounded once (LLVM's ``llvm.fma.f64``: the hardware instruction)."""
    signature = types.float64(types.float64, types.float64, types.float64)

    def codegen(context, builder, sig, args):
        return builder.fma(*args)

    return signature, codegen


@_jit
def _turn(x: float, z: float, c: float, s: float, fused: bool) -> tuple[float, float]:
    """Row ``(x, z)`` of ``points @ ((c, s), (-s, c))``: fused as OpenBLAS's ``dgemm``
    computes it when ``points`` has two or more rows, plain for numpy's single-row loop."""
    if fused:
        return _fma(z, -s, x * c), _fma(z, c, x * s)
    return x * c + z * -s, x * s + z * c


#: ``10**k`` as numpy's ``power_of_ten`` has it (exact up to ``k = 22``).
_POW10 = np.array([10.0**k for k in range(23)])


@_jit
def _round(x: float, decimals: int) -> float:
    """``np.round(x, decimals)`` (see :func:`._align.round_like_numpy`)."""
    if decimals >= 0:
        f = _POW10[decimals]
        return np.rint(x * f) / f
    f = _POW10[-decimals]
    return np.rint(x / f) * f


@_jit
def _pairwise(xs: np.ndarray) -> float:
    """numpy's ``pairwise_sum`` of ``xs`` (see :func:`._align.numpy_sum`): runs of up to 128
    summed by :func:`_run`, longer ones split in two at a multiple of 8 and the halves' sums
    added. Without recursion (numba's cache cannot reload a recursive function): a
    post-order walk of the halves with explicit stacks."""
    if xs.shape[0] <= 128:
        return _run(xs, 0, xs.shape[0])
    todo = [(0, xs.shape[0], False)]  # (start, length, halves already summed)
    sums = [0.0]
    sums.pop()
    while todo:
        lo, n, halves_done = todo.pop()
        if n <= 128:
            sums.append(_run(xs, lo, n))
        elif halves_done:
            right = sums.pop()
            sums.append(sums.pop() + right)
        else:
            half = n // 2
            half -= half % 8
            todo.append((lo, n, True))
            todo.append((lo + half, n - half, False))
            todo.append((lo, half, False))
    return sums[0]


@_jit
def _run(xs: np.ndarray, lo: int, n: int) -> float:
    """``pairwise_sum`` of ``xs[lo:lo + n]``, ``n <= 128``: in order below 8 values, else
    with 8 accumulators (``loops_utils.h``)."""
    if n < 8:
        total = 0.0
        for i in range(lo, lo + n):
            total += xs[i]
        return total
    r = xs[lo : lo + 8].copy()
    end = lo + n - n % 8
    for i in range(lo + 8, end, 8):
        for k in range(8):
            r[k] += xs[i + k]
    total = ((r[0] + r[1]) + (r[2] + r[3])) + ((r[4] + r[5]) + (r[6] + r[7]))
    for i in range(end, lo + n):
        total += xs[i]
    return total


@_jit
def _square(x: float, z: float, true: np.ndarray, j: int) -> float:
    """``dx**2 + dz**2`` from ``(x, z)`` to object ``j``, as numpy's ``diff *= diff`` and sum."""
    dx = x - true[j, 0]
    dz = z - true[j, 1]
    return dx * dx + dz * dz


@_jit
def fit(
    pred: np.ndarray, true: np.ndarray, pairs: np.ndarray
) -> tuple[float, float, float, float, float]:
    """:func:`._align.procrustes` of ``pred[r] -> true[c]`` for ``(r, c)`` in ``pairs``
    (k x 2, k >= 1), and the sum of squared residuals it leaves.

    As numpy computes them from the gathered ``(k x 2)`` arrays: centroids by
    ``sum(axis=0)`` (row after row), ``sum(a * b)`` and ``sum(a x b)`` pairwise, the angle by
    ``atan2`` (libm's, as Python's ``math``); residuals of the points moved as ``@ R`` (fused
    for two or more rows), squared per coordinate and summed pairwise. Returns
    ``(c, s, tx, tz, residual)``.
    """
    k = pairs.shape[0]
    px = pz = qx = qz = 0.0
    for i in range(k):
        px += pred[pairs[i, 0], 0]
        pz += pred[pairs[i, 0], 1]
        qx += true[pairs[i, 1], 0]
        qz += true[pairs[i, 1], 1]
    px, pz, qx, qz = px / k, pz / k, qx / k, qz / k
    dots = np.empty(2 * k)
    crosses = np.empty(k)
    for i in range(k):
        ax, az = pred[pairs[i, 0], 0] - px, pred[pairs[i, 0], 1] - pz
        bx, bz = true[pairs[i, 1], 0] - qx, true[pairs[i, 1], 1] - qz
        dots[2 * i] = ax * bx
        dots[2 * i + 1] = az * bz
        crosses[i] = ax * bz - az * bx
    dot, cross = 0.0 + _pairwise(dots), 0.0 + _pairwise(crosses)
    theta = math.atan2(cross, dot) if (dot != 0.0 or cross != 0.0) else 0.0
    c, s = math.cos(theta), math.sin(theta)
    tx, tz = qx - (c * px - s * pz), qz - (s * px + c * pz)
    squares = dots  # reused: 2k values
    for i in range(k):
        x, z = _turn(pred[pairs[i, 0], 0], pred[pairs[i, 0], 1], c, s, k >= 2)
        dx = (x + tx) - true[pairs[i, 1], 0]
        dz = (z + tz) - true[pairs[i, 1], 1]
        squares[2 * i] = dx * dx
        squares[2 * i + 1] = dz * dz
    return c, s, tx, tz, 0.0 + _pairwise(squares)


@_jit
def nearest_open(
    pred: np.ndarray,
    c: float,
    s: float,
    tx: float,
    tz: float,
    objects: Objects,
    decimals: int,
) -> tuple[bool, np.ndarray, np.ndarray]:
    """Each entry's nearest open object after the motion ``(c, s, tx, tz)``, as
    :func:`._align.assign` reads it.

    ``pred`` (n x 2) written points; ``objects`` the objects open to each (:data:`._align.Objects`).
    Returns ``(finite, nearest, distances)``: ``nearest[i]`` the first object at the least
    rounded squared distance (-1: none open), ``distances`` every (entry, open object)
    distance entry by entry. ``finite`` is False (and the rest unfinished) as soon as a
    distance is not finite: numpy's matrix then decides (:func:`._align.assign`).
    """
    kinds, starts, cols, true, held = objects
    fused = pred.shape[0] >= 2
    nearest = np.full(pred.shape[0], -1, dtype=np.intp)
    distances = np.empty(pred.shape[0] * true.shape[0])
    at = 0
    for i in range(pred.shape[0]):
        x, z = _turn(pred[i, 0], pred[i, 1], c, s, fused)
        x += tx
        z += tz
        k = kinds[i]
        low = np.inf
        for j in cols[starts[k] : starts[k + 1]]:
            if held[j]:
                continue
            v = _round(_square(x, z, true, j), decimals)
            if not v < np.inf:
                return False, nearest, distances
            distances[at] = v
            at += 1
            if v < low:
                nearest[i] = j
                low = v
    return True, nearest, distances[:at]


@_jit
def best_seed_index(seeds: np.ndarray, pred: np.ndarray, objects: Objects, decimals: int) -> int:
    """Index of the best seed of :func:`._align.undetermined_fit` among ``seeds`` (k x 4
    motions); every entry has an open object (arguments as :func:`nearest_open`).

    Per seed: each entry moved as ``c p + s (-z, x) + t``, its least squared distance to an
    object of its type (``np.minimum``, NaN first), summed over entries pairwise, rounded;
    the first least score wins (a NaN score first of all, as ``argmin`` has it).
    """
    kinds, starts, cols, true, held = objects
    n = pred.shape[0]
    least = np.empty(n)
    best, low = 0, np.inf
    for q in range(seeds.shape[0]):
        c, s, tx, tz = seeds[q, 0], seeds[q, 1], seeds[q, 2], seeds[q, 3]
        for i in range(n):
            x, z = pred[i, 0], pred[i, 1]
            mx = c * x + s * -z + tx
            mz = c * z + s * x + tz
            m = np.nan
            first = True
            for j in cols[starts[kinds[i]] : starts[kinds[i] + 1]]:
                if held[j]:
                    continue
                v = _square(mx, mz, true, j)
                if first or (not np.isnan(m) and (np.isnan(v) or v < m)):  # np.minimum
                    m = v
                first = False
            least[i] = m
        score = _round(0.0 + _pairwise(least), decimals)
        if np.isnan(score):
            return q
        if score < low:
            best, low = q, score
    return best


@_jit
def linear_sum_assignment(cost: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """:func:`scipy.optimize.linear_sum_assignment` of a finite ``cost`` (nr x nc, no NaN):
    ``(rows, cols)``, rows ascending, the same pairs as scipy's for every matrix, ties included.

    scipy's ``rectangular_lsap.cpp`` step by step (Crouse's shortest augmenting path, the
    Jonker-Volgenant variant without initialisation): a tall matrix is solved transposed;
    each row in turn grows a shortest path over the columns not yet scanned, taken in the
    order ``nc - 1, ..., 0`` then as swapped-in, the first least reduced cost winning except
    that a free column wins an equal cost; duals updated as scipy does, in its float order
    (``min + c - u - v``, no multiplication so nothing to fuse). Returns two empty arrays
    when no assignment is feasible (scipy raises; an infinite cost only).
    """
    nr, nc = cost.shape
    none = np.empty(0, dtype=np.intp)
    if nr == 0 or nc == 0:
        return none, none
    transpose = nc < nr
    c = np.ascontiguousarray(cost.T) if transpose else cost
    if transpose:
        nr, nc = nc, nr
    u = np.zeros(nr)
    v = np.zeros(nc)
    shortest = np.empty(nc)
    path = np.full(nc, -1, dtype=np.intp)
    col4row = np.full(nr, -1, dtype=np.intp)
    row4col = np.full(nc, -1, dtype=np.intp)
    scanned_rows = np.zeros(nr, dtype=np.bool_)
    scanned_cols = np.zeros(nc, dtype=np.bool_)
    remaining = np.empty(nc, dtype=np.intp)
    for current in range(nr):
        least = 0.0
        left = nc
        for it in range(nc):
            remaining[it] = nc - it - 1
        scanned_rows[:] = False
        scanned_cols[:] = False
        shortest[:] = np.inf
        sink = -1
        i = current
        while sink == -1:
            index = -1
            lowest = np.inf
            scanned_rows[i] = True
            for it in range(left):
                j = remaining[it]
                r = least + c[i, j] - u[i] - v[j]
                if r < shortest[j]:
                    path[j] = i
                    shortest[j] = r
                if shortest[j] < lowest or (shortest[j] == lowest and row4col[j] == -1):
                    lowest = shortest[j]
                    index = it
            least = lowest
            if least == np.inf:
                return none, none
            j = remaining[index]
            if row4col[j] == -1:
                sink = j
            else:
                i = row4col[j]
            scanned_cols[j] = True
            left -= 1
            remaining[index] = remaining[left]
        u[current] += least
        for i in range(nr):
            if scanned_rows[i] and i != current:
                u[i] += least - shortest[col4row[i]]
        for j in range(nc):
            if scanned_cols[j]:
                v[j] -= least - shortest[j]
        j = sink
        while True:
            i = path[j]
            row4col[j] = i
            col4row[i], j = j, col4row[i]
            if i == current:
                break
    if transpose:
        order = np.argsort(col4row)  # distinct values: every sort gives scipy's order
        return col4row[order], order.astype(np.intp)
    return np.arange(nr), col4row


@_jit
def assign_open(
    pred: np.ndarray,
    c: float,
    s: float,
    tx: float,
    tz: float,
    objects: Objects,
    decimals: int,
) -> tuple[bool, np.ndarray]:
    """:func:`._align.assign` after the motion ``(c, s, tx, tz)`` (arguments as
    :func:`nearest_open`): each entry's object, -1 for none.

    Each entry takes its nearest open object (:func:`nearest_open`); for the types where two
    entries share one, the type's entries (in entry order) and open objects (ascending) go
    through :func:`linear_sum_assignment` on their rounded squared distances. Returns
    ``(finite, objects)``; ``finite`` False as in :func:`nearest_open` (nothing decided).
    """
    finite, nearest, distances = nearest_open(pred, c, s, tx, tz, objects, decimals)
    if not finite:
        return False, nearest
    kinds, starts, cols, true, held = objects
    n = nearest.shape[0]
    owner = np.full(true.shape[0], -1, dtype=np.intp)
    clash = np.zeros(starts.shape[0] - 1, dtype=np.bool_)
    clashes = False
    for i in range(n):
        j = nearest[i]
        if j >= 0:
            if owner[j] >= 0:
                clash[kinds[i]] = True
                clashes = True
            owner[j] = i
    if not clashes:
        return True, nearest
    # where each entry's distances start: entries before it, one per object open to them
    open_count = np.zeros(starts.shape[0] - 1, dtype=np.intp)
    for k in range(open_count.shape[0]):
        for j in cols[starts[k] : starts[k + 1]]:
            if not held[j]:
                open_count[k] += 1
    start = np.empty(n, dtype=np.intp)
    at = 0
    for i in range(n):
        start[i] = at
        at += open_count[kinds[i]]
    for k in range(clash.shape[0]):
        if not clash[k]:
            continue
        rows = np.array([i for i in range(n) if kinds[i] == k], dtype=np.intp)
        free = np.array([j for j in cols[starts[k] : starts[k + 1]] if not held[j]], dtype=np.intp)
        width = free.shape[0]
        block = np.empty((rows.shape[0], width))
        for r in range(rows.shape[0]):
            block[r] = distances[start[rows[r]] : start[rows[r]] + width]
        for i in rows:
            nearest[i] = -1
        r_of, c_of = linear_sum_assignment(block)
        for q in range(r_of.shape[0]):
            nearest[rows[r_of[q]]] = free[c_of[q]]
    return True, nearest


@_jit
def refine(
    pred: np.ndarray,
    c: float,
    s: float,
    tx: float,
    tz: float,
    objects: Objects,
    decimals: int,
    zero_at: float,
    rounds: int,
) -> tuple[bool, np.ndarray]:
    """:func:`._align.refine` from the seed ``(c, s, tx, tz)``: :func:`assign_open`, then up to
    ``rounds`` times the :func:`fit` of the pairs and :func:`assign_open` again, stopping when
    no entry is assigned, when the residual rounds to zero (``<= zero_at``,
    :func:`._align.zero_below`) or when the assignment repeats. Returns ``(finite, objects)``
    as :func:`assign_open` (``finite`` False: some round met a distance that is not finite).
    """
    finite, pairs = assign_open(pred, c, s, tx, tz, objects, decimals)
    if not finite:
        return False, pairs
    true = objects[3]
    n = pairs.shape[0]
    for _ in range(rounds):
        k = 0
        for i in range(n):
            if pairs[i] >= 0:
                k += 1
        if k == 0:
            break
        index = np.empty((k, 2), dtype=np.intp)
        k = 0
        for i in range(n):
            if pairs[i] >= 0:
                index[k, 0] = i
                index[k, 1] = pairs[i]
                k += 1
        c, s, tx, tz, sse = fit(pred, true, index)
        if sse <= zero_at:
            break
        finite, again = assign_open(pred, c, s, tx, tz, objects, decimals)
        if not finite:
            return False, again
        same = True
        for i in range(n):
            if again[i] != pairs[i]:
                same = False
                break
        if same:
            break
        pairs = again
    return True, pairs
