"""Joint correspondence + rigid alignment of one cognitive map onto the ground truth.

The geometric half of :func:`pytest_emrd.metrics.match_map` (the procedure is stated in
:mod:`pytest_emrd.metrics._match`). Everything here is *equivariant*: moving every written
point by one proper rigid motion ``S`` moves every motion estimated here by ``S^-1`` and
leaves every correspondence unchanged, because each choice only compares quantities that a
rigid motion preserves (distances between written points, distances between ground-truth
points, squared residuals after a fit).
"""

from __future__ import annotations

import functools
import math
from collections.abc import Sequence
from dataclasses import dataclass, field
from typing import Final, NamedTuple

import numpy as np

#: Relative precision (of the problem's extent) at which residuals and distances are
#: compared, so that ties break the same way in every frame and on every machine.
TIE_DECIMALS: Final = 9
#: Written points closer than this (metres) carry no direction: they cannot fix a rotation.
COINCIDENT_M: Final = 1e-6
#: Most correspondence hypotheses scored when no anchors determine the frame.
MAX_HYPOTHESES: Final = 8
#: Most alternations of assignment and refit (each lowers the residual).
MAX_ROUNDS: Final = 8

Point = tuple[float, float]
Pairs = tuple[tuple[int, int], ...]
"""``(entry index, object index)`` pairs, sorted."""


class Motion(NamedTuple):
    """A proper rigid motion ``x -> R(theta) x + t`` as ``(cos, sin, tx, tz)``."""

    c: float
    s: float
    tx: float
    tz: float

    def __call__(self, x: float, z: float) -> Point:
        return self.c * x - self.s * z + self.tx, self.s * x + self.c * z + self.tz


def procrustes(pred: np.ndarray, true: np.ndarray) -> Motion:
    """Optimal proper rigid motion taking ``pred`` onto ``true`` (n x 2 each, n >= 1).

    2-D orthogonal Procrustes without scaling or reflection (Kabsch with ``det R = +1``):
    for centred points the angle maximising ``sum_j q_j . R p_j`` is
    ``atan2(sum p x q, sum p . q)``. One point, or coincident points: the identity rotation
    and the translation between centroids.
    """
    n = len(pred)
    pc = pred.sum(axis=0) / n
    qc = true.sum(axis=0) / n
    a = pred - pc
    b = true - qc
    dot = float((a * b).sum())
    cross = float((a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]).sum())
    theta = math.atan2(cross, dot) if (dot or cross) else 0.0
    c, s = math.cos(theta), math.sin(theta)
    return Motion(
        c, s, float(qc[0] - (c * pc[0] - s * pc[1])), float(qc[1] - (s * pc[0] + c * pc[1]))
    )


def two_point(pa: Point, pb: Point, qa: Point, qb: Point) -> Motion:
    """:func:`procrustes` of the two correspondences ``pa -> qa``, ``pb -> qb``."""
    ux, uz = pb[0] - pa[0], pb[1] - pa[1]
    vx, vz = qb[0] - qa[0], qb[1] - qa[1]
    theta = math.atan2(ux * vz - uz * vx, ux * vx + uz * vz)
    c, s = math.cos(theta), math.sin(theta)
    mx, mz = (pa[0] + pb[0]) / 2, (pa[1] + pb[1]) / 2
    nx, nz = (qa[0] + qb[0]) / 2, (qa[1] + qb[1]) / 2
    return Motion(c, s, nx - (c * mx - s * mz), nz - (s * mx + c * mz))


@functools.cache
def digits(scale: float, power: int) -> int:
    """Decimals comparing a quantity in metres**power at :data:`TIE_DECIMALS` relative."""
    return TIE_DECIMALS - power * math.ceil(math.log10(max(scale, 1.0)))


@dataclass(frozen=True)
class Problem:
    """One map's recognised entries against the ground truth."""

    pred: np.ndarray
    """Written positions of the recognised entries (n x 2), in entry order."""
    kinds: np.ndarray
    """Type index of each entry (n)."""
    true: np.ndarray
    """Ground-truth positions of every object (m x 2), objects sorted by id."""
    true_kinds: np.ndarray
    """Type index of each object (m)."""
    scale: float
    """Extent of the layout (metres), for relative tie tolerances."""
    true_points: tuple[Point, ...] = ()
    """``true`` as tuples (for :func:`hypotheses`)."""
    cols_of: dict[int, tuple[int, ...]] = field(default_factory=dict)
    """Type index -> its object indices (for :func:`hypotheses`)."""

    @functools.cached_property
    def allowed(self) -> np.ndarray:
        """(n x m) True where entry ``i`` and object ``j`` have the same type."""
        return self.kinds[:, None] == self.true_kinds[None, :]


def moved(points: np.ndarray, motion: Motion) -> np.ndarray:
    """``points`` (n x 2) after ``motion``."""
    c, s, tx, tz = motion
    return points @ np.array([[c, s], [-s, c]]) + np.array([tx, tz])


def assign(problem: Problem, motion: Motion) -> Pairs:
    """Per type, the one-to-one assignment minimising summed squared distances after ``motion``.

    Exactly ``min(|entries_k|, |objects_k|)`` pairs per type. Where every entry's nearest
    object of its type is a different one, that is the optimum (each term is at its own
    minimum); types where two entries want the same object go through
    :func:`scipy.optimize.linear_sum_assignment`. Squared distances are rounded to
    :data:`TIE_DECIMALS` relative digits; ties go to the lowest object index (id order).
    """
    p = moved(problem.pred, motion)
    q = problem.true
    d = (p[:, None, 0] - q[None, :, 0]) ** 2 + (p[:, None, 1] - q[None, :, 1]) ** 2
    d = np.where(problem.allowed, np.round(d, digits(problem.scale, 2)), np.inf)
    # An entry with no object of its type left (every one held by a carried identity) has an
    # all-inf row, whose argmin would name object 0 of another type: it stays unmatched.
    open_rows = np.isfinite(d).any(axis=1).tolist()
    nearest = [j if ok else -1 for j, ok in zip(d.argmin(axis=1).tolist(), open_rows, strict=True)]
    taken = [j for j in nearest if j >= 0]
    if len(set(taken)) == len(taken):
        return tuple((i, j) for i, j in enumerate(nearest) if j >= 0)
    from scipy.optimize import linear_sum_assignment  # heavy: imported on first use

    kinds = problem.kinds.tolist()
    seen: dict[int, int] = {}
    clash: set[int] = set()
    for i, j in enumerate(nearest):
        if j >= 0 and j in seen:
            clash.add(kinds[i])
        seen[j] = i
    pairs = [(i, j) for i, j in enumerate(nearest) if j >= 0 and kinds[i] not in clash]
    for k in sorted(clash):
        rows = np.flatnonzero(problem.kinds == k)
        cols = np.flatnonzero(problem.true_kinds == k)
        r, c = linear_sum_assignment(d[rows][:, cols])
        pairs += zip(rows[r].tolist(), cols[c].tolist(), strict=True)
    return tuple(sorted(pairs))


def _sse(problem: Problem, pairs: Pairs) -> tuple[float, Motion]:
    p = problem.pred[[r for r, _ in pairs]]
    q = problem.true[[c for _, c in pairs]]
    motion = procrustes(p, q)
    return round(float(((moved(p, motion) - q) ** 2).sum()), digits(problem.scale, 2)), motion


def refine(problem: Problem, seed: Motion) -> Pairs:
    """Alternate :func:`assign` and Procrustes refit from ``seed`` (ICP with known types).

    Each round lowers (or keeps) the sum of squared residuals; stops when the assignment
    repeats, when the fit is exact, or after :data:`MAX_ROUNDS`.
    """
    pairs = assign(problem, seed)
    for _ in range(MAX_ROUNDS):
        if not pairs:
            break
        sse, motion = _sse(problem, pairs)
        if sse == 0.0:
            break
        again = assign(problem, motion)
        if again == pairs:
            break
        pairs = again
    return pairs


def hypotheses(problem: Problem) -> list[Motion]:
    """Seeds for an undetermined frame, from correspondences of a frame-free base pair.

    The base entry ``a`` has the fewest candidate objects (ties: farthest from the written
    centroid, then entry order); the second ``b`` has the fewest candidates among entries not
    coincident with ``a`` (ties: farthest from ``a``). Every pair of distinct candidates
    ``(o_a, o_b)`` gives the motion fitting ``a -> o_a, b -> o_b``; the
    :data:`MAX_HYPOTHESES` whose ground-truth distance best matches the written one are kept
    (ties: object order). When no entry can serve as ``b`` (every entry coincides with ``a``,
    or all share ``a``'s single object) no rotation can be read: translations ``a -> o_a``.
    """
    pred: list[Point] = [(x, z) for x, z in problem.pred.tolist()]
    true = problem.true_points
    cand = [problem.cols_of[k] for k in problem.kinds.tolist()]
    d1 = digits(problem.scale, 1)
    cx = math.fsum(p[0] for p in pred) / len(pred)
    cz = math.fsum(p[1] for p in pred) / len(pred)
    order = range(len(pred))
    a = min(order, key=lambda i: (len(cand[i]), -round(math.dist(pred[i], (cx, cz)), d1)))
    gap = [round(math.dist(pred[i], pred[a]), d1) for i in order]
    # b needs a direction (not coincident with a) and an object other than a's
    others = [i for i in order if gap[i] > COINCIDENT_M and len({*cand[a], *cand[i]}) > 1]
    if not others:
        return [Motion(1.0, 0.0, true[o][0] - pred[a][0], true[o][1] - pred[a][1]) for o in cand[a]]
    b = min(others, key=lambda i: (len(cand[i]), -gap[i]))
    options = sorted(
        (round(abs(math.dist(true[oa], true[ob]) - gap[b]), d1), oa, ob)
        for oa in cand[a]
        for ob in cand[b]
        if oa != ob
    )
    return [
        two_point(pred[a], pred[b], true[oa], true[ob]) for _, oa, ob in options[:MAX_HYPOTHESES]
    ]


def undetermined_fit(problem: Problem, first: Sequence[Motion] = ()) -> Pairs:
    """Correspondence of a map whose frame no anchors determine: a joint estimate.

    The seeds are ``first`` (the caller's tie-breakers, in order) followed by those of
    :func:`hypotheses`. Every seed is scored at once by the summed squared distance of each
    entry to its nearest object of its type after the seed's motion; the best seed (ties: the
    first) is refined by :func:`refine`.
    """
    seeds = [*first, *hypotheses(problem)]
    if not seeds:
        return ()
    if len(seeds) > 1:
        m = np.array(seeds)
        p, q = problem.pred, problem.true
        mx = m[:, :1] * p[:, 0] - m[:, 1:2] * p[:, 1] + m[:, 2:3]
        mz = m[:, 1:2] * p[:, 0] + m[:, :1] * p[:, 1] + m[:, 3:4]
        d = (mx[:, :, None] - q[None, None, :, 0]) ** 2 + (
            mz[:, :, None] - q[None, None, :, 1]
        ) ** 2
        score = np.where(problem.allowed[None], d, np.inf).min(axis=2).sum(axis=1)
        seeds = [seeds[int(np.round(score, digits(problem.scale, 2)).argmin())]]
    return refine(problem, seeds[0])
