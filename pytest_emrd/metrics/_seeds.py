"""Each step's frame compiled: its seed and the assignment it gives, in one call.

:func:`anchored` is a determined frame (:meth:`._match.Matcher._in_frame`): the Procrustes fit
of the anchors onto their objects and the assignment of the other entries in it.
:func:`undetermined` is :func:`._align.undetermined_fit`: the seeds of the
caller's known pairs (:func:`known_seed`), the correspondence hypotheses of a base pair
(:func:`hypotheses`), the best seed (:func:`._kernels.best_seed_index`) and its refinement
(:func:`._kernels.refine`). Distances, sums and roundings that choose the base pair and order
the hypotheses are Python's (:mod:`._pyfloat`), so every choice is the one specified and
made before in Python (oracle: ``tests/metrics/test_seeds.py``).

Imported on first use only, with numba (:func:`._align.compiled`).
"""

from __future__ import annotations

import math

import numpy as np

from pytest_emrd.metrics._align import Objects
from pytest_emrd.metrics._kernels import _jit, assign_open, best_seed_index, fit, refine
from pytest_emrd.metrics._pyfloat import dist, fsum, round_half_even


@_jit
def anchored(
    points: np.ndarray,
    anchors: np.ndarray,
    kinds: np.ndarray,
    held: np.ndarray,
    starts: np.ndarray,
    cols: np.ndarray,
    true: np.ndarray,
    decimals: int,
) -> tuple[bool, np.ndarray, tuple[float, float, float, float]]:
    """The anchors' frame and the entries assigned in it.

    ``points`` (n x 2): the anchors' written points (their objects ``anchors``, a >= 1), then
    those of the entries to assign (types ``kinds``); ``held``: objects open to none of them.
    The motion is :func:`._kernels.fit` of the anchors onto their objects (in order), the
    assignment :func:`._kernels.assign_open` among the objects not held (``starts``, ``cols``,
    ``true`` as in :data:`._align.Objects`). Returns ``(finite, objects, motion)`` as
    :func:`._kernels.assign_open`, with the motion ``(c, s, tx, tz)``.
    """
    a = anchors.shape[0]
    pairs = np.empty((a, 2), dtype=np.intp)
    for i in range(a):
        pairs[i, 0], pairs[i, 1] = i, anchors[i]
    c, s, tx, tz, _ = fit(points, true, pairs)
    mask = np.zeros(true.shape[0], dtype=np.bool_)
    for j in held:
        mask[j] = True
    pred = points[a:].copy()
    finite, found = assign_open(pred, c, s, tx, tz, (kinds, starts, cols, true, mask), decimals)
    return finite, found, (c, s, tx, tz)


@_jit
def _apart(pred: np.ndarray, pairs: np.ndarray, coincident: float) -> bool:
    """Whether some entry of ``pairs`` is farther than ``coincident`` (``math.dist``) from the
    first one's written point."""
    r0 = pairs[0, 0]
    for i in range(pairs.shape[0]):
        r = pairs[i, 0]
        if dist(pred[r0, 0], pred[r0, 1], pred[r, 0], pred[r, 1]) > coincident:
            return True
    return False


@_jit
def known_seed(
    pred: np.ndarray, true: np.ndarray, pairs: np.ndarray, coincident: float, out: np.ndarray
) -> bool:
    """The fit of known ``(entry, object)`` ``pairs`` (k x 2, k >= 1) into ``out`` (4: a motion):
    Procrustes (:func:`._kernels.fit`) of two or more written points not all coincident; the
    translation of the first pair when they coincide, or for one pair. False (no seed) when
    coincident points name different objects: no direction can be read."""
    if pairs.shape[0] == 1 or not _apart(pred, pairs, coincident):
        r, c = pairs[0, 0], pairs[0, 1]
        for i in range(pairs.shape[0]):
            if pairs[i, 1] != c:
                return False
        out[0], out[1] = 1.0, 0.0
        out[2], out[3] = true[c, 0] - pred[r, 0], true[c, 1] - pred[r, 1]
        return True
    out[0], out[1], out[2], out[3], _ = fit(pred, true, pairs)
    return True


@_jit
def _two_point(
    ax: float, az: float, bx: float, bz: float, qa: np.ndarray, qb: np.ndarray, out: np.ndarray
) -> None:
    """Procrustes of ``a -> qa``, ``b -> qb`` into ``out``: the angle between the written and
    the true direction, the midpoints matched."""
    ux, uz = bx - ax, bz - az
    vx, vz = qb[0] - qa[0], qb[1] - qa[1]
    theta = math.atan2(ux * vz - uz * vx, ux * vx + uz * vz)
    c, s = math.cos(theta), math.sin(theta)
    mx, mz = (ax + bx) / 2, (az + bz) / 2
    nx, nz = (qa[0] + qb[0]) / 2, (qa[1] + qb[1]) / 2
    out[0], out[1] = c, s
    out[2], out[3] = nx - (c * mx - s * mz), nz - (s * mx + c * mz)


@_jit
def _open_of(objects: Objects, k: int) -> np.ndarray:
    """The objects of type ``k`` open to an entry, ascending."""
    _, starts, cols, _, held = objects
    found = np.empty(starts[k + 1] - starts[k], dtype=np.intp)
    n = 0
    for j in cols[starts[k] : starts[k + 1]]:
        if not held[j]:
            found[n] = j
            n += 1
    return found[:n]


@_jit
def hypotheses(
    pred: np.ndarray, objects: Objects, d1: int, most: int, coincident: float, out: np.ndarray
) -> int:
    """Seeds for an undetermined frame, from correspondences of a frame-free base pair, written
    into ``out`` (rows of 4); returns how many.

    The base entry ``a`` has the fewest open objects (ties: farthest from the written
    centroid, ``math.fsum`` of each coordinate over the entries, then entry order); the second
    ``b`` has the fewest open objects among entries farther than ``coincident`` from ``a`` and
    not sharing ``a``'s single object (ties: farthest from ``a``); distances are
    ``math.dist`` rounded to ``d1`` decimals (``round``). Every pair of distinct objects
    ``(o_a, o_b)`` open to them gives the motion fitting ``a -> o_a, b -> o_b``; the ``most``
    whose ground-truth distance best matches the written one are kept (ties: object order).
    When no entry can serve as ``b``: the translations ``a -> o_a``, every ``o_a``.
    """
    kinds, _, _, true, _ = objects
    n = pred.shape[0]
    sizes = np.empty(n, dtype=np.intp)
    for i in range(n):
        sizes[i] = _open_of(objects, kinds[i]).shape[0]
    cx, cz = fsum(pred[:, 0].copy()) / n, fsum(pred[:, 1].copy()) / n
    fewest = sizes.min()
    a, far = -1, 0.0
    for i in range(n):
        if sizes[i] == fewest:
            g = round_half_even(dist(pred[i, 0], pred[i, 1], cx, cz), d1)
            if a < 0 or g > far:
                a, far = i, g
    ax, az = pred[a, 0], pred[a, 1]
    b, least, gap = -1, np.inf, 0.0
    for i in range(n):
        size = sizes[i]
        if size > least or (size == 1 and kinds[i] == kinds[a]):
            continue
        g = round_half_even(dist(pred[i, 0], pred[i, 1], ax, az), d1)
        if g > coincident and (size < least or g > gap):
            b, least, gap = i, size, g
    open_a = _open_of(objects, kinds[a])
    if b < 0:
        for q in range(open_a.shape[0]):
            o = open_a[q]
            out[q, 0], out[q, 1] = 1.0, 0.0
            out[q, 2], out[q, 3] = true[o, 0] - ax, true[o, 1] - az
        return open_a.shape[0]
    open_b = _open_of(objects, kinds[b])
    keys = np.empty(open_a.shape[0] * open_b.shape[0])
    pairs = np.empty((keys.shape[0], 2), dtype=np.intp)
    count = 0
    for oa in open_a:
        for ob in open_b:
            if oa != ob:
                span = dist(true[oa, 0], true[oa, 1], true[ob, 0], true[ob, 1])
                keys[count] = round_half_even(abs(span - gap), d1)
                pairs[count, 0], pairs[count, 1] = oa, ob
                count += 1
    # stable: pairs were listed in (o_a, o_b) order, the tie order
    order = np.argsort(keys[:count], kind="mergesort")
    kept = min(count, most)
    for q in range(kept):
        oa, ob = pairs[order[q], 0], pairs[order[q], 1]
        _two_point(ax, az, pred[b, 0], pred[b, 1], true[oa], true[ob], out[q])
    return kept


@_jit
def undetermined(
    pred: np.ndarray,
    objects: Objects,
    kept: np.ndarray,
    named: np.ndarray,
    d1: int,
    decimals: int,
    zero_at: float,
    rounds: int,
    most: int,
    coincident: float,
) -> tuple[bool, np.ndarray, np.ndarray]:
    """:func:`._align.undetermined_fit`: the seeds (``kept``'s, then ``named``'s, each when
    given and readable, then :func:`hypotheses`), the best of them
    (:func:`._kernels.best_seed_index`; the first when there is one seed or an entry has no
    open object), refined (:func:`._kernels.refine`). Returns ``(finite, objects, seed)`` as
    :func:`._kernels.refine`, and the seed refined; no seed at all gives every entry -1."""
    kinds, _, _, true, _ = objects
    n = pred.shape[0]
    seeds = np.empty((2 + max(most, true.shape[0]), 4))
    count = 0
    for pairs in (kept, named):
        if pairs.shape[0] and known_seed(pred, true, pairs, coincident, seeds[count]):
            count += 1
    count += hypotheses(pred, objects, d1, most, coincident, seeds[count:])
    if count == 0:
        return True, np.full(n, -1, dtype=np.intp), np.zeros(4)
    best = 0
    if count > 1:
        every = True
        for i in range(n):
            if _open_of(objects, kinds[i]).shape[0] == 0:
                every = False
        if every:
            best = best_seed_index(seeds[:count], pred, objects, decimals)
    c, s, tx, tz = seeds[best]
    finite, found = refine(pred, c, s, tx, tz, objects, decimals, zero_at, rounds)
    return finite, found, seeds[best].copy()
