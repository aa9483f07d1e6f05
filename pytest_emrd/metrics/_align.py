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
and scipy expressions they replace (oracles: ``tests/metrics/test_align.py``); so is the
whole undetermined frame (:mod:`._seeds`: the seeds, with Python's ``math.dist``,
``math.fsum`` and ``round`` compiled bitwise in :mod:`._pyfloat`; oracle:
``tests/metrics/test_seeds.py``).
"""

from __future__ import annotations

import functools
import importlib
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
    return compiled().fit(pred, true, pair_array(pairs))


def pair_array(pairs: Sequence[tuple[int, int]]) -> np.ndarray:
    """``(entry, object)`` pairs as a (k x 2) index array."""
    flat = np.fromiter(itertools.chain.from_iterable(pairs), np.intp, 2 * len(pairs))
    flat.shape = (len(pairs), 2)
    return flat


@functools.cache
def compiled(module: str = "_kernels") -> ModuleType:
    """A compiled module of the metrics (:mod:`._kernels`, :mod:`._seeds`, :mod:`._copies`),
    imported (with numba) on first use."""
    return importlib.import_module(f"pytest_emrd.metrics.{module}")


@functools.cache
def digits(scale: float, power: int) -> int:
    """Decimals comparing a quantity in metres**power at :data:`TIE_DECIMALS` relative."""
    return TIE_DECIMALS - power * math.ceil(math.log10(max(scale, 1.0)))


class Layout(NamedTuple):
    """The ground truth every map of an episode is aligned onto (objects sorted by id)."""

    true: np.ndarray
    """Object positions (m x 2)."""
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


def undetermined_fit(
    problem: Problem, kept: Sequence[tuple[int, int]] = (), named: Sequence[tuple[int, int]] = ()
) -> Pairs:
    """Correspondence of a map whose frame no anchors determine: a joint estimate.

    The seeds are the fits of ``kept`` and of ``named`` (the caller's known ``(entry,
    object)`` pairs, its tie-breakers, in that order; :func:`._seeds.known_seed`), then the
    correspondence hypotheses of a frame-free base pair (:func:`._seeds.hypotheses`, at most
    :data:`MAX_HYPOTHESES`). The seed whose motion leaves the smallest summed squared distance
    of each entry to its nearest open object of its type wins (rounded to
    :data:`TIE_DECIMALS` relative digits; ties: the first; an entry no object can take makes
    every score infinite: the first seed) and is refined by :func:`refine`. Computed by
    :func:`._seeds.undetermined` in one call; a distance that is not finite leaves the
    refinement to :func:`refine`'s matrix path.
    """
    d1, d2 = digits(problem.layout.scale, 1), digits(problem.layout.scale, 2)
    finite, found, seed = compiled("_seeds").undetermined(
        problem.pred, problem.open, pair_array(kept), pair_array(named), d1, d2,
        zero_below(d2), MAX_ROUNDS, MAX_HYPOTHESES, COINCIDENT_M,
    )  # fmt: skip
    if finite:
        return tuple([(i, j) for i, j in enumerate(found.tolist()) if j >= 0])
    return refine(problem, Motion(*seed.tolist()))
