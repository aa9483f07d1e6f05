"""Joint correspondence + rigid alignment of one cognitive map onto the ground truth.

The geometric half of :func:`pytest_emrd.metrics.match_map` (the procedure is stated in
:mod:`pytest_emrd.metrics._match`). Everything here is *equivariant*: moving every written
point by one proper rigid motion ``S`` moves every motion estimated here by ``S^-1`` and
leaves every correspondence unchanged, because each choice only compares quantities that a
rigid motion preserves (distances between written points, distances between ground-truth
points, squared residuals after a fit).

The loops every step runs (each entry's nearest open object after a motion, the optimal
assignment where two entries want one object, the seeds' scores, the Procrustes fit) are
compiled (:mod:`._kernels`, numba, loaded on the first match) and give the bits of the numpy
and scipy expressions they replace (oracles: ``tests/metrics/test_align.py``).
"""

from __future__ import annotations

import functools
import itertools
import math
from collections.abc import Sequence
from types import ModuleType
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

Objects = tuple[np.ndarray, np.ndarray, np.ndarray, np.ndarray, np.ndarray]
"""The objects open to a map's entries: the type index of each entry (n), the layout's
object indices by type (``starts``, ``cols``: type ``k``'s objects are
``cols[starts[k]:starts[k + 1]]``, ascending), its positions (m x 2), which objects are held
(m booleans). See :attr:`Problem.open`."""

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


def procrustes(pred: np.ndarray, true: np.ndarray, pairs: Sequence[tuple[int, int]]) -> Motion:
    """Optimal proper rigid motion taking ``pred[r]`` onto ``true[c]`` for the ``(r, c)`` in
    ``pairs`` (one or more; ``pred``, ``true``: (n x 2) arrays).

    2-D orthogonal Procrustes without scaling or reflection (Kabsch with ``det R = +1``):
    for centred points the angle maximising ``sum_j q_j . R p_j`` is
    ``atan2(sum p x q, sum p . q)``. One point, or coincident points: the identity rotation
    and the translation between centroids. Computed by :func:`._kernels.fit`, bitwise the
    numpy expression on the gathered points (oracle: ``tests/metrics/test_align.py``).
    """
    return Motion(*fit(pred, true, pairs)[:4])


def fit(
    pred: np.ndarray, true: np.ndarray, pairs: Sequence[tuple[int, int]]
) -> tuple[float, float, float, float, float]:
    """:func:`procrustes` as ``(c, s, tx, tz)`` and the sum of squared residuals it leaves
    (:func:`._kernels.fit`)."""
    return compiled().fit(pred, true, np.array(pairs, dtype=np.intp).reshape(-1, 2))


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
def compiled() -> ModuleType:
    """:mod:`._kernels`, imported (with numba) on first use."""
    from pytest_emrd.metrics import _kernels

    return _kernels


@functools.cache
def digits(scale: float, power: int) -> int:
    """Decimals comparing a quantity in metres**power at :data:`TIE_DECIMALS` relative."""
    return TIE_DECIMALS - power * math.ceil(math.log10(max(scale, 1.0)))


class Layout(NamedTuple):
    """The ground truth every map of an episode is aligned onto (objects sorted by id)."""

    true: np.ndarray
    """Object positions (m x 2)."""
    points: tuple[Point, ...]
    """``true`` as tuples."""
    kinds: np.ndarray
    """Type index of each object (m)."""
    cols_of: dict[int, tuple[int, ...]]
    """Type index -> its object indices, ascending."""
    scale: float
    """Extent of the layout (metres), for relative tie tolerances."""
    starts: np.ndarray
    """``cols_of`` for the kernels: type ``k``'s objects are ``cols[starts[k]:starts[k+1]]``."""
    cols: np.ndarray
    """Object indices grouped by type, ascending within each type."""
    free: np.ndarray
    """m False: no object held."""


def layout_of(points: Sequence[Point], kinds: Sequence[int], scale: float) -> Layout:
    """The :class:`Layout` of objects at ``points`` (m) of type indices ``kinds`` (m)."""
    cols_of: dict[int, tuple[int, ...]] = {}
    for c, k in enumerate(kinds):
        cols_of[k] = (*cols_of.get(k, ()), c)
    top = max(kinds, default=-1) + 1
    counts = [len(cols_of.get(k, ())) for k in range(top)]
    return Layout(
        np.array(points, dtype=float).reshape(-1, 2),
        tuple((float(x), float(z)) for x, z in points),
        np.array(kinds, dtype=np.intp),
        cols_of,
        scale,
        np.array([0, *itertools.accumulate(counts)], dtype=np.intp),
        np.array([c for k in range(top) for c in cols_of.get(k, ())], dtype=np.intp),
        np.zeros(len(points), dtype=bool),
    )


class Problem:
    """One map's recognised entries against the objects still open to them."""

    __slots__ = ("_blocked", "_candidates", "held", "kinds", "layout", "open", "points", "pred")

    def __init__(
        self,
        points: list[Point],
        kinds: list[int],
        layout: Layout,
        held: Sequence[int] = (),
    ) -> None:
        self.points = points
        """Written positions of the recognised entries, in entry order."""
        self.pred = np.fromiter(itertools.chain.from_iterable(points), float, 2 * len(points))
        self.pred.shape = (len(points), 2)
        """``points`` as an (n x 2) array."""
        self.kinds = kinds
        """Type index of each entry."""
        self.layout = layout
        self.held = held
        """Objects open to no entry (held by carried identities)."""
        mask = layout.free
        if held:
            mask = mask.copy()
            mask[list(held)] = True
        self.open: Objects = (
            np.array(kinds, dtype=np.intp), layout.starts, layout.cols, layout.true, mask,
        )  # fmt: skip
        """The objects open to each entry as the kernels read them (:data:`Objects`)."""
        self._candidates: list[tuple[int, ...]] | None = None
        self._blocked: np.ndarray | None = None

    @property
    def candidates(self) -> list[tuple[int, ...]]:
        """The objects open to each entry, ascending."""
        if self._candidates is None:
            cols_of = self.layout.cols_of
            if self.held:
                gone = set(self.held)
                cols_of = {
                    k: tuple(c for c in cols_of.get(k, ()) if c not in gone) for k in self.kinds
                }
            self._candidates = [cols_of.get(k, ()) for k in self.kinds]
        return self._candidates

    @property
    def blocked(self) -> np.ndarray:
        """(n x m) True where object ``j`` is not open to entry ``i`` (another type, held)."""
        if self._blocked is None:
            true_kinds = self.layout.kinds
            if self.held:
                true_kinds = true_kinds.copy()
                true_kinds[list(self.held)] = -1
            self._blocked = np.array(self.kinds, dtype=int)[:, None] != true_kinds
        return self._blocked


def moved(points: np.ndarray, motion: Motion) -> np.ndarray:
    """``points`` (n x 2) after ``motion``."""
    c, s, tx, tz = motion
    out = points @ np.array(((c, s), (-s, c)))
    out += (tx, tz)
    return out


def assign(problem: Problem, motion: Motion) -> Pairs:
    """Per type, the one-to-one assignment minimising summed squared distances after ``motion``.

    Exactly ``min(|entries_k|, |objects_k|)`` pairs per type. Where every entry's nearest
    object of its type is a different one, that is the optimum (each term is at its own
    minimum); types where two entries want the same object go through
    :func:`scipy.optimize.linear_sum_assignment`. Squared distances are rounded to
    :data:`TIE_DECIMALS` relative digits; ties go to the lowest object index (id order).
    Computed by :func:`._kernels.assign_open` (scipy's assignment ported step by step, same
    pairs, ties included); a distance that is not finite leaves it for numpy's matrix and
    scipy itself.
    """
    dec = digits(problem.layout.scale, 2)
    finite, found = compiled().assign_open(problem.pred, *motion, problem.open, dec)
    if finite:
        return tuple([(i, j) for i, j in enumerate(found.tolist()) if j >= 0])
    d = _distance_matrix(problem, moved(problem.pred, motion), dec)
    # An entry with no object of its type left (every one held by a carried identity) has
    # an all-inf row, whose argmin would name object 0 of another type: it stays unmatched.
    open_rows = np.isfinite(d).any(axis=1).tolist()
    best = d.argmin(axis=1).tolist()
    nearest = [j if ok else -1 for j, ok in zip(best, open_rows, strict=True)]
    taken = [j for j in nearest if j >= 0]
    if len(set(taken)) == len(taken):
        return tuple((i, j) for i, j in enumerate(nearest) if j >= 0)
    from scipy.optimize import linear_sum_assignment  # heavy: imported on first use

    kinds = problem.kinds
    seen: dict[int, int] = {}
    clash: set[int] = set()
    for i, j in enumerate(nearest):
        if j >= 0 and j in seen:
            clash.add(kinds[i])
        seen[j] = i
    pairs = [(i, j) for i, j in enumerate(nearest) if j >= 0 and kinds[i] not in clash]
    for k in sorted(clash):
        rows = [i for i, kind in enumerate(kinds) if kind == k]
        cols = list(problem.candidates[rows[0]])
        r, c = linear_sum_assignment(d[rows][:, cols])
        pairs += ((rows[i], cols[j]) for i, j in zip(r.tolist(), c.tolist(), strict=True))
    return tuple(sorted(pairs))


def _distance_matrix(problem: Problem, p: np.ndarray, dec: int) -> np.ndarray:
    """(n x m) rounded squared distances ``dx**2 + dz**2`` of the moved entries ``p`` to every
    object, inf where the object is not open to the entry."""
    diff = p[:, None, :] - problem.layout.true
    diff *= diff
    d = diff[..., 0] + diff[..., 1]
    d = d.round(dec, out=d)
    np.copyto(d, np.inf, where=problem.blocked)
    return d


def _sse(problem: Problem, pairs: Pairs) -> tuple[float, Motion]:
    c, s, tx, tz, sse = fit(problem.pred, problem.layout.true, pairs)
    return round(sse, digits(problem.layout.scale, 2)), Motion(c, s, tx, tz)


@functools.cache
def zero_below(decimals: int) -> float:
    """The largest float ``x`` with ``round(x, decimals) == 0.0`` (Python's correctly rounded
    ``round``): a non-negative ``x`` rounds to zero exactly when ``x <= zero_below(decimals)``,
    which a compiled loop can test."""
    x = 0.5 * 10.0**-decimals
    while round(x, decimals) != 0.0:
        x = math.nextafter(x, 0.0)
    while round(math.nextafter(x, math.inf), decimals) == 0.0:
        x = math.nextafter(x, math.inf)
    return x


def refine(problem: Problem, seed: Motion) -> Pairs:
    """Alternate :func:`assign` and Procrustes refit from ``seed`` (ICP with known types).

    Each round lowers (or keeps) the sum of squared residuals; stops when the assignment
    repeats, when the fit is exact (the residual rounds to zero), or after
    :data:`MAX_ROUNDS`. Run by :func:`._kernels.refine`; a distance that is not finite
    leaves it for the same loop over :func:`assign` here.
    """
    dec = digits(problem.layout.scale, 2)
    finite, found = compiled().refine(
        problem.pred, *seed, problem.open, dec, zero_below(dec), MAX_ROUNDS
    )
    if finite:
        return tuple([(i, j) for i, j in enumerate(found.tolist()) if j >= 0])
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
    pred = problem.points
    true = problem.layout.points
    cand = problem.candidates
    d1 = digits(problem.layout.scale, 1)
    n = len(pred)
    centre = (math.fsum([p[0] for p in pred]) / n, math.fsum([p[1] for p in pred]) / n)
    sizes = [len(cols) for cols in cand]
    fewest = min(sizes)
    a, far = -1, 0.0
    for i, size in enumerate(sizes):
        if size == fewest:
            g = round(math.dist(pred[i], centre), d1)
            if a < 0 or g > far:
                a, far = i, g
    # b needs a direction (not coincident with a) and an object other than a's
    b, best, gap = -1, (math.inf, 0.0), 0.0
    pa = pred[a]
    for i, cols in enumerate(cand):
        size = sizes[i]
        if size > best[0] or (size == 1 and cols == cand[a]):
            continue
        g = round(math.dist(pred[i], pa), d1)
        if g > COINCIDENT_M and (size, -g) < best:
            b, best, gap = i, (size, -g), g
    if b < 0:
        return [Motion(1.0, 0.0, true[o][0] - pred[a][0], true[o][1] - pred[a][1]) for o in cand[a]]
    options = sorted(
        (round(abs(math.dist(true[oa], true[ob]) - gap), d1), oa, ob)
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
    :func:`hypotheses`; the :func:`best_seed` is refined by :func:`refine`.
    """
    seeds = [*first, *hypotheses(problem)]
    if not seeds:
        return ()
    return refine(problem, best_seed(problem, seeds))


def best_seed(problem: Problem, seeds: Sequence[Motion]) -> Motion:
    """The seed whose motion leaves the smallest summed squared distance of each entry to its
    nearest object of its type (rounded to :data:`TIE_DECIMALS` relative digits; ties: the
    first), computed by :func:`._kernels.best_seed_index`. An entry no object can take makes
    every score infinite: the first seed.
    """
    if len(seeds) == 1 or not all(problem.candidates):
        return seeds[0]
    best = compiled().best_seed_index(
        np.array(seeds), problem.pred, problem.open, digits(problem.layout.scale, 2)
    )
    return seeds[best]
