"""SIR's copies compiled: what each entry written during a re-entry means, in one call.

:func:`meant` is the geometric half of :func:`._scores.reentry_copies`, giving the bits of the
numpy and scipy expressions it replaced (oracle: ``tests/metrics/test_copies.py``): the
alignment is :func:`._kernels.fit` (``rigid_fit``), a group of new entries is moved as
``points @ R.T + t`` is by OpenBLAS (``dgemm`` for two or more rows, whose kernel fuses
``z * R[0, 1]`` into ``x * R[0, 0]``; ``dgemv`` for one row, which fuses the other way round),
squared distances are ``np.round``-ed (:func:`._kernels._round`) and paired by
:func:`._kernels.linear_sum_assignment` (scipy's, step by step).

Imported on first use only, with numba (:func:`._align.compiled`).
"""

from __future__ import annotations

import math

import numpy as np

from pytest_emrd.metrics._kernels import _fma, _jit, _round, fit, linear_sum_assignment

#: :func:`meant`'s outcomes besides ``OK``.
OK, COINCIDENT, INVALID, INFEASIBLE = 0, 1, 2, 3


@_jit
def _moved(x: float, z: float, c: float, s: float, rows: int) -> tuple[float, float]:
    """Row ``(x, z)`` of ``points @ R.T`` for ``R = ((c, -s), (s, c))`` of ``rows`` rows."""
    if rows >= 2:
        return _fma(z, -s, x * c), _fma(z, c, x * s)
    return _fma(x, c, z * -s), _fma(x, s, z * c)


@_jit
def meant(
    pred: np.ndarray,
    true: np.ndarray,
    new: np.ndarray,
    kinds: np.ndarray,
    starts: np.ndarray,
    cols: np.ndarray,
    spots: np.ndarray,
    decimals: int,
    coincident: float,
) -> tuple[int, np.ndarray]:
    """The object each new entry means, and an outcome.

    ``pred``, ``true`` (k x 2, k >= 2): the matched entries' written points and their
    objects'; ``new`` (q x 2): the new entries, grouped by type (``kinds``, q) in the caller's
    order; the objects of type ``k`` are ``cols[starts[k]:starts[k + 1]]`` at ``spots``.
    Outcomes: ``COINCIDENT`` when every matched written point lies within ``coincident`` of
    the first (``np.hypot``; no rotation can be read); ``INVALID`` / ``INFEASIBLE`` where scipy
    raises (a NaN squared distance; no assignment of finite cost); else ``OK`` and, per new
    entry, the object paired with it one to one within its group at the least total rounded
    squared distance after the alignment, or for entries beyond the group's object count
    the first nearest (``argmin``).
    """
    q = new.shape[0]
    found = np.full(q, -1, dtype=np.intp)
    far = 0.0
    for i in range(pred.shape[0]):  # np.max of np.hypot: NaN wins
        d = math.hypot(pred[i, 0] - pred[0, 0], pred[i, 1] - pred[0, 1])
        if d > far or math.isnan(d):
            far = d
            if math.isnan(d):
                break
    if far <= coincident:
        return COINCIDENT, found
    index = np.empty((pred.shape[0], 2), dtype=np.intp)
    for i in range(pred.shape[0]):
        index[i, 0] = index[i, 1] = i
    c, s, tx, tz, _ = fit(pred, true, index)
    lo = 0
    while lo < q:
        k = kinds[lo]
        hi = lo
        while hi < q and kinds[hi] == k:
            hi += 1
        objects = cols[starts[k] : starts[k + 1]]
        cost = np.empty((hi - lo, objects.shape[0]))
        for r in range(hi - lo):
            x, z = _moved(new[lo + r, 0], new[lo + r, 1], c, s, hi - lo)
            x, z = x + tx, z + tz
            for j in range(objects.shape[0]):
                dx, dz = x - spots[objects[j], 0], z - spots[objects[j], 1]
                cost[r, j] = _round(dx * dx + dz * dz, decimals)
                if math.isnan(cost[r, j]):
                    return INVALID, found
        rows, picked = linear_sum_assignment(cost)
        if rows.shape[0] == 0:
            return INFEASIBLE, found
        for t in range(rows.shape[0]):
            found[lo + rows[t]] = objects[picked[t]]
        for r in range(hi - lo):
            if found[lo + r] < 0:
                found[lo + r] = objects[np.argmin(cost[r])]
        lo = hi
    return OK, found
