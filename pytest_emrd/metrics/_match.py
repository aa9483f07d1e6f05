"""Label-to-ground-truth matching: the one procedure every metric uses.

A model writes its cognitive map as ``{label: {type, x, z, room}}`` with labels and types of
its own, in a frame of its own. :func:`match_map` decides which object each entry of one map
stands for, from that map alone:

1. **Entries.** Every entry counts: a label written again (a map given as a list) is one
   more entry, keyed ``"<label> #<n>"`` (the ``n``-th time it is written; the first free key).
2. **Types** (:mod:`._vocab`): the entry's ``object_type``, else its label, restricted to the
   layout's types; an entry of no such type is *unrecognised* and takes no part below.
3. **Frame** (:func:`_solve`): hypotheses are the rigid motions carrying two base entries
   (:data:`BASE_ENTRIES`, fewest candidate objects first, one entry of each type in turn)
   onto two objects of their types whose distance agrees within ``2 * GATE_M``. The
   :data:`CANDIDATES` with the least truncated least-squares score (MSAC: an entry costs its
   squared distance to the nearest object of its type, capped at ``GATE_M ** 2``; on equal
   scores, the most labels that are object ids, ``Chair_3``, within the gate of their
   object) and, across steps, the previous frame are each refined: assignment and
   Procrustes refit (:func:`rigid_fit`) on the matched pairs alternate until the pairs
   repeat. **The matching PA scores highest is kept** (Eq. PA, :func:`pa_value`, with the
   episode's ``|G_base|``), then the one with most pairs, then with most id labels on their
   own object, then the first: the frame is chosen by the quantity PA reports. Entries are
   ordered by type and distance from their centroid (:data:`Key`), so that neither the
   frame, the order of the entries nor a synonym moves a score.
4. **Assignment with a gate** (:data:`GATE_M`): the one-to-one assignment with the most pairs,
   then the least summed squared distance, rounded to :data:`TIE_M2` first (the tie rule).

Recognised entries left without a pair are *unmatched* (Eq. PA's charge). The matching is
invariant under proper rigid motions; reflections are not forgiven. **Across steps**
(:meth:`Matcher.step`: TBS, spells, SIR) the previous frame and pairs are extended to new or
moved entries when they explain them all, otherwise the full search runs with the previous
frame as one more hypothesis (also when a frame found on fewer than :data:`SETTLED` entries
has grown by :data:`REVISIT`); a label keeps its previous object on exact ties. The docs page
"Map and memory metrics a model cannot fool" gives each rule's reason and measured effect.
:func:`reframe` moves every map entry of an episode by one rigid motion (or a mirror).
"""

from __future__ import annotations

import functools
import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass, field, replace
from itertools import combinations
from typing import Final, NamedTuple

import numpy as np

from pytest_emrd.metrics._vocab import TypeResolver
from pytest_emrd.trajectory import GroundTruthObject, MapEntry, Trajectory

#: Largest distance (metres, after alignment) at which an entry may stand for an object.
GATE_M: Final = 1.5
#: Squared distances are rounded to this (m^2) before any comparison: the tie rule.
TIE_M2: Final = 1e-9
#: Written points closer than this (metres) carry no direction: they cannot fix a rotation.
COINCIDENT_M: Final = 1e-6
#: Entries (fewest candidate objects first) whose pairs seed the frame hypotheses.
BASE_ENTRIES: Final = 6
#: Most alternations of assignment and refit.
MAX_ROUNDS: Final = 10
#: Across steps, a frame searched for on fewer than :data:`SETTLED` entries is searched for
#: again once the map has grown by this factor (an early frame read from a few entries is
#: revisited as the map grows).
REVISIT: Final = 1.5
SETTLED: Final = 12

#: Frame hypotheses (least MSAC score first) refined into matchings; the one PA scores
#: highest is kept (step 3).
CANDIDATES: Final = 6
#: Share of a map's recognised entries that may stay unmatched at no cost to PA (one stray
#: entry in a full office map of 41 costs nothing; spraying guesses does).
FREE_UNMATCHED: Final = 0.05
#: PA values closer than this are equal (the first candidate wins): the tie rule of step 3.
TIE_PA: Final = 1e-12

_UNITS_GATE: Final = round(GATE_M**2 / TIE_M2)
_FORBIDDEN: Final = 1e15  # cost of a pair outside the gate: more than any sum of allowed ones


@dataclass(frozen=True)
class MatchedPair:
    """One map entry assigned to one ground-truth object."""

    label: str
    object_id: str
    object_type: str
    pred_x: float
    """The model's coordinates, as written."""
    pred_z: float
    true_x: float
    """Ground truth, spawn frame."""
    true_z: float


@dataclass(frozen=True)
class Matching:
    """Result of :func:`match_map` (see the module docstring for the procedure)."""

    pairs: tuple[MatchedPair, ...]
    """Matched pairs ``K``, ordered by object id."""
    unmatched: tuple[str, ...]
    """Recognised labels left without an object (type exhausted, or none within the gate)."""
    unrecognised: tuple[str, ...]
    """Labels whose type resolves to no ground-truth type (sorted)."""
    duplicates: tuple[str, ...]
    """Labels written more than once; each later copy is an entry of its own (``label #n``)."""
    covered: int
    """``sum_k min(|M_k|, |E_k|)`` over the layout's types, ``|M_k|`` the distinct labels of
    type ``k``: Eq. AEC's numerator."""

    @property
    def object_ids(self) -> frozenset[str]:
        return frozenset(p.object_id for p in self.pairs)

    @property
    def label_of(self) -> dict[str, str]:
        """Object id -> the label matched to it."""
        return {p.object_id: p.label for p in self.pairs}

    @property
    def entries(self) -> int:
        """Entries of the map, same-label copies included: matched, unmatched, unrecognised."""
        return len(self.pairs) + len(self.unmatched) + len(self.unrecognised)


EMPTY_MATCHING: Final = Matching((), (), (), (), 0)


class Motion(NamedTuple):
    """A proper rigid motion ``x -> R(theta) x + t`` as ``(cos, sin, tx, tz)``."""

    c: float
    s: float
    tx: float
    tz: float


def _procrustes(pred: np.ndarray, true: np.ndarray) -> Motion:
    """Optimal proper rigid motion taking ``pred`` (k x 2) onto ``true`` (k x 2)."""
    cp, cq = pred.mean(axis=0), true.mean(axis=0)
    a, b = pred - cp, true - cq
    dot = float(np.sum(a * b))
    cross = float(np.sum(a[:, 0] * b[:, 1] - a[:, 1] * b[:, 0]))
    theta = math.atan2(cross, dot) if math.hypot(dot, cross) > COINCIDENT_M**2 else 0.0
    c, s = math.cos(theta), math.sin(theta)
    tx, tz = cq - _moved(cp[None], Motion(c, s, 0.0, 0.0))[0]
    return Motion(c, s, tx, tz)


def rigid_fit(pred: np.ndarray, true: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    r"""Optimal proper rigid motion (rotation + translation) taking ``pred`` onto ``true``.

    2-D orthogonal Procrustes without scaling or reflection (Kabsch with ``det R = +1``):
    for centred points ``a_j``, ``b_j`` the rotation maximising ``sum_j b_j . R a_j`` has
    angle ``atan2(sum a x b, sum a . b)``, and ``t = mean(b) - R mean(a)``. One point, or all
    points coincident: the identity rotation and the translation between centroids.

    :param pred: The matched entries' positions, k x 2.
    :param true: Their objects' positions, row by row.
    :returns: ``(R, t)``: a 2 x 2 rotation and a translation, ``aligned = pred @ R.T + t``.
    """
    pred = np.asarray(pred, dtype=float).reshape(-1, 2)
    true = np.asarray(true, dtype=float).reshape(-1, 2)
    m = _procrustes(pred, true)
    return np.array([[m.c, -m.s], [m.s, m.c]]), np.array([m.tx, m.tz])


def layout_scale(xy: np.ndarray) -> float:
    """RMS distance of points from their centroid (``L_gt``); 0.0 for fewer than 2 points.

    :param xy: Points, k x 2.
    :returns: ``L_gt`` in metres.
    """
    if len(xy) < 2:
        return 0.0
    return float(np.sqrt(np.mean(_spread(xy))))


def _spread(xy: np.ndarray) -> np.ndarray:
    """Squared distance of each point (k x 2) from the points' centroid."""
    return np.sum((xy - xy.mean(axis=0)) ** 2, axis=1)


def exp_ratio(error: float, scale: float) -> float:
    """``exp(-error / scale)`` with ``0/0 := 0`` (perfect) and ``x/0 := inf`` (score 0)."""
    if error <= 0.0:
        return 1.0
    if scale <= 0.0:
        return 0.0
    return math.exp(-error / scale)


def pa_coverage(matched: int, unmatched: int, g_base: int) -> float:
    r"""The coverage factor of Eq. PA with our charge for unmatched entries.

    .. math::
        c = \frac{\max\left(0,\ \min(|K|, |G_{base}|) - u\right)}{|G_{base}|},\qquad
        u = \max\left(0,\ |U| - \lfloor 0.05\,(|K| + |U|) \rfloor\right)

    ``U`` are the recognised entries left unmatched (:attr:`Matching.unmatched`, every
    same-label copy included): each one beyond :data:`FREE_UNMATCHED` of the recognised
    entries cancels one matched object, so a guess pays only if more than half of such
    guesses land within the gate of a free object. Without unmatched entries this is the
    paper's factor.

    :param matched: ``|K|``, entries matched to an object.
    :param unmatched: ``|U|``, recognised entries left without one.
    :param g_base: ``|G_base|``, the objects discoverable under the baseline.
    :returns: ``c`` in [0, 1]; 0.0 when ``g_base = 0``.
    """
    if g_base == 0:
        return 0.0
    charged = max(0, unmatched - math.floor(FREE_UNMATCHED * (matched + unmatched)))
    return max(0, min(matched, g_base) - charged) / g_base


def pa_value(pred: np.ndarray, true: np.ndarray, unmatched: int, g_base: int) -> float:
    """Eq. PA of matched points ``pred`` -> ``true`` (k x 2): what
    :func:`~pytest_emrd.metrics.positional_accuracy_score` reports and step 3 maximises.

    :param pred: The matched entries as written, k x 2.
    :param true: Their objects, row by row.
    :param unmatched: ``|U|``, charged by :func:`pa_coverage`.
    :param g_base: ``|G_base|``.
    :returns: ``exp(-RMSE / L_gt) * c`` in [0, 1]; 0.0 without pairs or with ``g_base = 0``.
    """
    if not len(pred) or g_base == 0:
        return 0.0
    m = _procrustes(pred, true)
    residual = _moved(pred, m) - true
    rmse = float(np.sqrt(np.mean(np.sum(residual**2, axis=1))))
    if rmse < 1e-9 * max(1.0, float(np.abs(true).max())):
        rmse = 0.0
    return exp_ratio(rmse, layout_scale(true)) * pa_coverage(len(pred), unmatched, g_base)


def _moved(points: np.ndarray, m: Motion) -> np.ndarray:
    x, z = points[:, 0], points[:, 1]
    return np.stack([m.c * x - m.s * z + m.tx, m.s * x + m.c * z + m.tz], axis=1)


def _units(d2: np.ndarray) -> np.ndarray:
    """Squared distances in units of :data:`TIE_M2`, rounded (the tie rule)."""
    return np.round(d2 / TIE_M2)


Pairs = tuple[tuple[int, int], ...]
"""``(entry row, object column)`` pairs, sorted."""


class _Problem:
    """One map's recognised entries (:data:`Key`) against the layout."""

    def __init__(self, key: Key, layout: _Layout):
        self.kinds = [k for _, k, _, _ in key]
        self.pred = np.array([(x, z) for _, _, x, z in key], dtype=float)
        self.layout = layout
        self.same = np.asarray(self.kinds, dtype=int)[:, None] == layout.kinds[None, :]
        rows, cols = np.nonzero(self.same)
        self.candidates = rows, cols  # every (entry, object of its type), by entry
        self.starts = np.searchsorted(rows, np.arange(len(key)))  # each entry's first one


@dataclass(frozen=True)
class _Layout:
    true: np.ndarray
    """Object positions (m x 2), objects sorted by id."""
    kinds: np.ndarray
    """Type index of each object."""
    cols_of: dict[int, tuple[int, ...]]
    """Type index -> its objects, ascending."""
    g_base: int
    """``|G_base|`` of Eq. PA, the quantity step 3 maximises."""
    _pairs: dict[tuple[int, int], tuple[np.ndarray, np.ndarray]] = field(default_factory=dict)

    def pairs_of(self, ka: int, kb: int) -> tuple[np.ndarray, np.ndarray]:
        """Every ``(o_a, o_b)`` of distinct objects of types ``ka``, ``kb`` (k x 2, in
        ``(o_a, o_b)`` order) and their distances."""
        found = self._pairs.get((ka, kb))
        if found is None:
            pairs = np.array(
                [(i, j) for i in self.cols_of[ka] for j in self.cols_of[kb] if i != j], dtype=int
            ).reshape(-1, 2)
            v = self.true[pairs[:, 1]] - self.true[pairs[:, 0]]
            found = self._pairs[(ka, kb)] = (pairs, np.hypot(v[:, 0], v[:, 1]))
        return found


def assign_rows(cost: np.ndarray, allowed: np.ndarray) -> list[tuple[int, int]]:
    """The one-to-one pairs ``(row, col)`` among ``allowed`` ones: the most pairs, then the
    least summed ``cost`` (:func:`scipy.optimize.linear_sum_assignment`). When every row's
    cheapest allowed column (the first on equal costs) is a different one, that is the
    optimum and scipy is not needed (nor imported: it costs a cold process half a second)."""
    rows = np.flatnonzero(allowed.any(axis=1))
    if not len(rows):
        return []
    masked = np.where(allowed, cost, np.inf)[rows]
    best = masked.argmin(axis=1)
    if len(np.unique(best)) == len(best):
        return list(zip(rows.tolist(), best.tolist(), strict=True))
    from scipy.optimize import linear_sum_assignment  # heavy: imported on first conflict

    cols = np.flatnonzero(allowed[rows].any(axis=0))
    block = np.where(allowed[np.ix_(rows, cols)], cost[np.ix_(rows, cols)], _FORBIDDEN)
    r, c = linear_sum_assignment(block)
    return [
        (int(rows[i]), int(cols[j])) for i, j in zip(r, c, strict=True) if allowed[rows[i], cols[j]]
    ]


def _assign(problem: _Problem, motion: Motion, prefer: np.ndarray | None) -> Pairs:
    """Step 4: the gated one-to-one assignment after ``motion`` (most pairs, then least
    rounded squared distance; ``prefer`` (n x m) lowers a carried pair by half a unit)."""
    moved = _moved(problem.pred, motion)
    diff = moved[:, None, :] - problem.layout.true[None, :, :]
    cost = _units(np.sum(diff * diff, axis=2))
    allowed = problem.same & (cost <= _UNITS_GATE)
    if prefer is not None:
        cost = cost - 0.5 * prefer
    return tuple(sorted(assign_rows(cost, allowed)))


def _refit(problem: _Problem, pairs: Pairs, motion: Motion) -> tuple[Motion, bool]:
    """Procrustes on the pairs (flag True), or with fewer than two distinct points the current
    rotation, translated to put the first pair's entry on its object."""
    p = problem.pred[[i for i, _ in pairs]]
    q = problem.layout.true[[j for _, j in pairs]]
    if len(pairs) >= 2 and np.ptp(p, axis=0).max() > COINCIDENT_M:
        return _procrustes(p, q), True
    moved = _moved(p[:1], motion)[0]
    return motion._replace(
        tx=motion.tx + q[0, 0] - moved[0], tz=motion.tz + q[0, 1] - moved[1]
    ), False


def _refine(
    problem: _Problem, motion: Motion, prefer: np.ndarray | None, read: bool
) -> tuple[Pairs, Motion, bool]:
    """Alternate assignment and refit until the pairs repeat; ``read`` (returned updated):
    the rotation was read from the map."""
    pairs = _assign(problem, motion, prefer)
    for _ in range(MAX_ROUNDS):
        if not pairs:
            break
        motion, fitted = _refit(problem, pairs, motion)
        read = read or fitted
        again = _assign(problem, motion, prefer)
        if again == pairs:
            break
        pairs = again
    return pairs, motion, read


def _hypotheses(problem: _Problem) -> tuple[np.ndarray, bool]:
    """Frame hypotheses (step 3) as rows ``(c, s, tx, tz)``; the flag is False when no pair
    of entries gives a direction (translations only, the model frame's own rotation)."""
    layout, pred = problem.layout, problem.pred
    kinds = problem.kinds
    spread = _units(_spread(pred)).tolist()
    order = sorted(range(len(kinds)), key=lambda i: (len(layout.cols_of[kinds[i]]), -spread[i], i))
    taken: Counter[int] = Counter()  # one entry of each type in turn: copies of a type
    turn: dict[int, int] = {}  # cannot crowd the others out
    for i in order:
        taken[kinds[i]] += 1
        turn[i] = taken[kinds[i]]
    base = sorted(order, key=turn.__getitem__)[:BASE_ENTRIES]
    true = layout.true
    rows = [np.zeros((0, 4), dtype=int)]  # (entry a, entry b, object o_a, object o_b)
    for a, b in combinations(base, 2):
        dist = math.dist(pred[a], pred[b])
        if dist > COINCIDENT_M:
            pairs, span = layout.pairs_of(kinds[a], kinds[b])
            near = pairs[np.abs(span - dist) <= 2 * GATE_M]
            rows.append(np.column_stack([np.full((len(near), 2), (a, b)), near]))
    ab = np.concatenate(rows)
    if not len(ab):  # one entry, or coincident entries: no direction to read
        cols = list(layout.cols_of[kinds[base[0]]])
        shift = true[cols] - pred[base[0]]
        return np.column_stack([np.ones(len(cols)), np.zeros(len(cols)), shift]), False
    pa, pb, qa, qb = pred[ab[:, 0]], pred[ab[:, 1]], true[ab[:, 2]], true[ab[:, 3]]
    u, v = pb - pa, qb - qa
    theta = np.arctan2(u[:, 0] * v[:, 1] - u[:, 1] * v[:, 0], np.sum(u * v, axis=1))
    c, s = np.cos(theta), np.sin(theta)
    shift = (qa + qb) / 2 - _moved((pa + pb) / 2, Motion(c, s, 0.0, 0.0))  # midpoint onto midpoint
    return np.column_stack([c, s, shift]), True


def _scores(problem: _Problem, motions: np.ndarray) -> np.ndarray:
    """MSAC score of each motion (rows ``(c, s, tx, tz)``): summed capped squared distance of
    every entry to the nearest object of its type, in rounded units."""
    rows, cols = problem.candidates
    moved = _moved(problem.pred[rows], Motion(*motions.T[:, :, None]))  # motion x axis x candidate
    d2 = np.sum((moved - problem.layout.true[cols].T) ** 2, axis=1)
    nearest = np.minimum.reduceat(d2, problem.starts, axis=1)
    return np.minimum(_units(nearest), _UNITS_GATE).sum(axis=1)


def _solve(
    problem: _Problem,
    seeds: Sequence[Motion],
    prefer: np.ndarray | None,
    named: frozenset[tuple[int, int]],
) -> tuple[Pairs, Motion, bool]:
    """Step 3: of ``seeds`` and the best-scored hypotheses, refined, the matching PA scores
    highest, then with most pairs, then with most ``named`` pairs (labels that are the
    object's id), then the first; the flag: the result's rotation was read from a map."""
    motions, read = _hypotheses(problem)
    agree = np.zeros(len(motions))  # named entries within the gate of their object: a tie rule
    for i, j in named:
        d2 = (_moved(problem.pred[[i]], Motion(*motions.T)) - problem.layout.true[j]) ** 2
        agree -= _units(d2.sum(axis=1)) <= _UNITS_GATE
    order = np.lexsort((agree, _scores(problem, motions)))[:CANDIDATES]
    starts = [(m, True) for m in seeds] + [(Motion(*motions[i].tolist()), read) for i in order]

    @functools.cache  # matchings refined from several starts often repeat
    def rank(pairs: Pairs) -> tuple[float, int, int]:
        rows, cols = [i for i, _ in pairs], [j for _, j in pairs]
        value = pa_value(
            problem.pred[rows],
            problem.layout.true[cols],
            len(problem.kinds) - len(pairs),
            problem.layout.g_base,
        )
        return round(value / TIE_PA), len(pairs), len(named.intersection(pairs))

    refined = [_refine(problem, motion, prefer, was_read) for motion, was_read in starts]
    return max(refined, key=lambda found: rank(found[0]))  # the first of the best


Key = tuple[tuple[str, int, float, float], ...]
"""A map's recognised entries as ``(label, type index, x, z)``, ordered by type, then distance
from the entries' centroid (rounded to :data:`TIE_M2`), then label: an order that neither the
model's frame, nor the order it writes entries in, nor (but for entries of one type equally far
from the centroid) what it calls them changes."""


@dataclass(frozen=True, kw_only=True)
class StepMatch:
    """One map matched (what :meth:`Matcher.step` returns and takes back)."""

    entries: dict[str, MapEntry]
    """Entry key (the label; ``label #n`` for its ``n``-th copy) -> entry, in the model's
    order."""
    kind_of: dict[str, int]
    """Entry key -> type index (-1: unrecognised)."""
    identity: dict[str, int]
    """Label -> object index (objects sorted by id) of the object it stands for."""
    unmatched: tuple[str, ...]
    motion: Motion | None
    """The frame found (None: no recognised entry, or a frame whose rotation the map does
    not determine: one point, or points giving no direction; such a frame is not carried)."""
    key: Key
    solved: int
    """Recognised entries when the frame was last searched for (:meth:`Matcher._match`)."""


_Found = tuple[dict[str, int], tuple[str, ...], Motion | None, int]
"""What a map's matching adds to its entries: ``identity``, ``unmatched``, ``motion`` and
``solved`` of :class:`StepMatch`."""


def keyed(entries: Sequence[MapEntry]) -> dict[str, MapEntry]:
    """Every entry of a map under a key of its own (step 1 of the module docstring).

    :param entries: The map as written, in the model's order.
    :returns: The label for its first entry, ``"<label> #<n>"`` for the ``n``-th (the next free
        key when a label already is that text), in the model's order.
    """
    out: dict[str, MapEntry] = {}
    counts: Counter[str] = Counter()
    for e in entries:
        counts[e.label] += 1
        key, n = e.label, counts[e.label]
        while key in out:
            key, n = f"{e.label} #{n}", n + 1
        out[key] = e
    return out


class Matcher:
    """:func:`match_map` bound to one episode's ground truth, reusable across its steps."""

    def __init__(self, objects: Sequence[GroundTruthObject], g_base: int | None = None) -> None:
        self.objects = ordered = sorted(objects, key=lambda o: o.object_id)
        self.types = TypeResolver(o.object_type for o in ordered)
        kinds = [self.types.index[o.object_type] for o in ordered]
        cols_of = {
            k: tuple(j for j, kj in enumerate(kinds) if kj == k)
            for k in range(len(self.types.names))
        }
        true = np.array([(o.x, o.z) for o in ordered], dtype=float).reshape(-1, 2)
        g_base = len(ordered) if g_base is None else g_base
        self._layout = _Layout(true, np.array(kinds, dtype=int), cols_of, g_base)
        self._points: list[list[float]] = true.tolist()  # for per-point arithmetic in Python
        self._index = {o.object_id: j for j, o in enumerate(ordered)}

    def step(self, entries: Sequence[MapEntry], previous: StepMatch | None = None) -> StepMatch:
        """Match one step's map; ``previous`` (the step before) seeds the frame and breaks
        exact ties in favour of the labels' previous objects (module docstring)."""
        seen = keyed(entries)
        kind_of = {lb: self.types.resolve(e.object_type, e.label) for lb, e in seen.items()}
        rows = [
            (lb, k, float(seen[lb].x), float(seen[lb].z)) for lb, k in kind_of.items() if k >= 0
        ]
        xz = np.array([r[2:] for r in rows], dtype=float).reshape(-1, 2)
        spread = _units(_spread(xz)).tolist() if rows else []
        order = sorted(range(len(rows)), key=lambda i: (rows[i][1], spread[i], rows[i][0]))
        key = tuple(rows[i] for i in order)
        if previous is not None and previous.key == key:
            return replace(previous, entries=seen, kind_of=kind_of)
        found = (previous and self._extend(previous, key)) or self._match(key, previous)
        identity, unmatched, motion, solved = found
        return StepMatch(
            entries=seen,
            kind_of=kind_of,
            identity=identity,
            unmatched=unmatched,
            motion=motion,
            key=key,
            solved=solved,
        )

    def _extend(self, previous: StepMatch, key: Key) -> _Found | None:
        """The previous matching extended to the entries written or moved since, when each
        has a free object of its type within the gate and no freed object could take an
        unmatched entry; None otherwise."""
        motion = previous.motion
        if motion is None or len(previous.identity) < 3:
            return None
        if previous.solved < SETTLED and len(key) >= REVISIT * previous.solved:
            return None
        before = set(previous.key)
        held = previous.identity
        changed = [e for e in key if e not in before]
        kept = {e[0] for e in key if e in before}
        identity = {e[0]: held[e[0]] for e in key if e in before and e[0] in held}
        unmatched = tuple(lb for lb in previous.unmatched if lb in kept)
        cols_of = self._layout.cols_of
        taken = set(identity.values())
        freed = set(previous.identity.values()) - taken
        for _, k, x, z in (e for e in key if e[0] in unmatched):
            if self._nearest(motion, x, z, [j for j in cols_of[k] if j in freed]) >= 0:
                return None
        for lb, k, x, z in changed:
            best = self._nearest(motion, x, z, [j for j in cols_of[k] if j not in taken])
            if best < 0:
                return None
            identity[lb] = best
            taken.add(best)
        return identity, unmatched, motion, previous.solved

    def _nearest(self, motion: Motion, x: float, z: float, cols: list[int]) -> int:
        """The object of ``cols`` nearest to ``(x, z)`` after ``motion`` within the gate (-1:
        none); the first wins unless a later one is nearer by more than :data:`TIE_M2`."""
        c, s, tx, tz = motion
        px, pz = c * x - s * z + tx, s * x + c * z + tz
        best, least = -1, GATE_M**2 + TIE_M2
        points = self._points
        for j in cols:
            qx, qz = points[j]
            d2 = (px - qx) ** 2 + (pz - qz) ** 2
            if d2 < least - TIE_M2:
                best, least = j, d2
        return best

    def _match(self, key: Key, previous: StepMatch | None) -> _Found:
        """Steps 3-4 on the recognised entries ``key`` (see :meth:`step`)."""
        labels = [lb for lb, _, _, _ in key]
        if not labels:
            return {}, (), None, 0
        problem = _Problem(key, self._layout)
        prefer = None
        if previous is not None and previous.identity:
            prefer = np.zeros(problem.same.shape)
            for i, lb in enumerate(labels):
                j = previous.identity.get(lb)
                if j is not None and problem.same[i, j]:
                    prefer[i, j] = 1.0
        seeds = [] if previous is None or previous.motion is None else [previous.motion]
        named = [(i, self._index[lb]) for i, lb in enumerate(labels) if lb in self._index]
        named = [(i, j) for i, j in named if problem.same[i, j]]
        pairs, motion, read = _solve(problem, seeds, prefer, frozenset(named))
        identity = {labels[i]: j for i, j in pairs}
        unmatched = tuple(sorted(lb for lb in labels if lb not in identity))
        # A rotation the map did not determine is the model frame's own: carried to the next
        # step as a seed it would make that step's matching depend on the frame.
        kept = motion if read else None
        return identity, unmatched, kept, len(key)

    def matching(self, found: StepMatch) -> Matching:
        """The :class:`Matching` of one matched map."""
        pairs = []
        for lb, j in sorted(found.identity.items(), key=lambda item: item[1]):  # by object id
            o, e = self.objects[j], found.entries[lb]
            x, z = self._points[j]
            pairs.append(MatchedPair(lb, o.object_id, o.object_type, float(e.x), float(e.z), x, z))
        first_kind: dict[str, int] = {}  # Eq. AEC counts distinct labels: a label's first entry
        for lb, k in found.kind_of.items():
            first_kind.setdefault(found.entries[lb].label, k)
        per_type = Counter(k for k in first_kind.values() if k >= 0)
        capacity = self._layout.cols_of
        covered = sum(min(n, len(capacity[k])) for k, n in per_type.items())
        unrecognised = tuple(sorted(lb for lb, k in found.kind_of.items() if k < 0))
        counts = Counter(e.label for e in found.entries.values())
        duplicates = tuple(sorted(lb for lb, n in counts.items() if n > 1))
        return Matching(tuple(pairs), found.unmatched, unrecognised, duplicates, covered)

    def held(self, found: StepMatch) -> dict[str, str]:
        """Object id -> label of one matched map."""
        return {self.objects[j].object_id: lb for lb, j in found.identity.items()}

    def match(self, entries: Sequence[MapEntry]) -> Matching:
        """Match one cognitive map on its own (see the module docstring)."""
        return self.matching(self.step(entries))


def step_matchings(
    steps: Sequence[Sequence[MapEntry]], objects: Sequence[GroundTruthObject]
) -> tuple[Matching, ...]:
    """The matching of every step's map of an episode, as the per-step metrics see them
    (previous frame tried first, previous identities winning exact ties).

    :param steps: Every step's map, in step order.
    :param objects: The episode's ground truth.
    :returns: One :class:`Matching` per step.
    """
    matcher = Matcher(objects)
    out: list[Matching] = []
    previous: StepMatch | None = None
    for entries in steps:
        previous = matcher.step(entries, previous)
        out.append(matcher.matching(previous))
    return tuple(out)


def match_map(
    entries: Sequence[MapEntry], objects: Sequence[GroundTruthObject], *, g_base: int | None = None
) -> Matching:
    """Match a cognitive map to ground truth: THE procedure of every EMRD metric.

    See the module docstring of :mod:`pytest_emrd.metrics._match` for the steps, the gate,
    the frame rule and the tie rule. Depends on this map and the ground truth only.

    Edge cases: an empty map or an empty ground truth gives no pairs; entries of unknown type
    are listed in ``unrecognised``; a single entry and a single object of the same type always
    match; a single entry of a type with several instances takes the first of them by id (with
    one point nothing in the map can tell them apart); entries beyond their type's instance
    count, or beyond :data:`GATE_M` of every free object of their type, are ``unmatched``.

    Worked example: ``Desk_1`` at (0, 0), ``Desk_2`` at (1, 0), ``Door_1`` at (-3, 2); the map
    writes ``d1`` at (10, 10) and ``d2`` at (10, 11) (a frame turned by 90 degrees) and an
    "exit sign" of type ``Door`` at (10, 25), 15 m from the desks where the door is 4 m from
    them: the desks are matched (``d1`` -> ``Desk_1``), the sign is ``unmatched`` (no motion
    puts it within :data:`GATE_M` of the door while keeping the desks).

    :param entries: The cognitive map's entries.
    :param objects: The ground-truth objects.
    :param g_base: ``|G_base|`` for the coverage charge; None for ``len(objects)``.
    :returns: The :class:`Matching`: pairs, unmatched and unrecognised entries.
    """
    return Matcher(objects, g_base).match(entries)


def reframe(
    traj: Trajectory, theta: float, dx: float, dz: float, *, mirror: bool = False
) -> Trajectory:
    """``traj`` with every cognitive-map coordinate ``p`` replaced by ``R(theta) M p + t``.

    ``R(theta)`` rotates by ``theta`` radians, ``t = (dx, dz)`` translates, ``M`` mirrors
    ``x -> -x`` when ``mirror`` (an improper motion, which no metric forgives). One motion
    for the whole episode, as a model that picked another origin and heading would write.
    Steps that share a map object (a parse failure repeats the last map) still share it.

    :param traj: The episode whose maps move.
    :param theta: Rotation in radians.
    :param dx: Translation along x, metres.
    :param dz: Translation along z, metres.
    :param mirror: Mirror ``x -> -x`` before rotating.
    :returns: A new trajectory; everything but the map coordinates unchanged.
    """
    c, s = math.cos(theta), math.sin(theta)
    sign = -1.0 if mirror else 1.0
    moved: dict[int, tuple[MapEntry, ...]] = {}
    steps = []
    for step in traj.steps:
        key = id(step.cognitive_map)
        if key not in moved:
            moved[key] = tuple(
                replace(e, x=c * sign * e.x - s * e.z + dx, z=s * sign * e.x + c * e.z + dz)
                for e in step.cognitive_map
            )
        steps.append(replace(step, cognitive_map=moved[key]))
    return replace(traj, steps=tuple(steps))


def random_reframe(traj: Trajectory, rng: np.random.Generator) -> Trajectory:
    """:func:`reframe` with a proper motion drawn from ``rng``: a uniform heading and an
    origin uniform in ``[-100, 100]^2`` metres.

    :param traj: The episode to move, as for :func:`reframe`.
    :param rng: The generator the motion is drawn from.
    :returns: The reframed trajectory.
    """
    theta = float(rng.uniform(0.0, 2.0 * math.pi))
    dx, dz = (float(v) for v in rng.uniform(-100.0, 100.0, 2))
    return reframe(traj, theta, dx, dz)
