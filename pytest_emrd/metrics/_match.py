"""Label-to-ground-truth matching: the one procedure every metric uses.

A model writes its cognitive map as ``{label: {type, x, z, room}}`` with labels and types of
its own choosing and coordinates in a frame of its own: the paper's "arbitrary egocentric
origins", which it resolves "using an optimal rigid-body Procrustes alignment". Every metric
that needs to know *which physical object* a map entry stands for calls :func:`match_map`
(episodes: :class:`Matcher`, once per step), which decides, for the map ``M_t`` of one step
and from that map alone:

1. **Labels.** A label is one recorded instance; a repeated label keeps its first entry (the
   JSON map is keyed by label, so repeats only come from malformed input).
2. **Types** (:mod:`pytest_emrd.metrics._vocab`). The entry's ``object_type`` is read first,
   then its label, by :func:`~pytest_emrd.metrics.canonical_type` restricted to the types the
   layout holds. An entry that denotes no type of the layout is *unrecognised* (a
   hallucination): it is matched to nothing.
3. **Correspondence and alignment, jointly.** Among the assignments that pair, per type
   ``k``, exactly ``min(|M_k|, |E_k|)`` entries with distinct objects of type ``k`` (the
   paper's AEC cap), the one chosen is the one whose optimal proper rigid motion
   (Procrustes, :func:`rigid_fit`) leaves the smallest sum of squared residuals: the
   correspondence under which the map is most accurate, i.e. the RMSE of Eq. PA minimised
   over the correspondences the labels' types allow as well as over the motion. It is found
   by alternating per-type optimal assignment (:func:`scipy.optimize.linear_sum_assignment`)
   and Procrustes refit from *frame-free seeds*:

   * **Determined frame.** When the map holds two or more *anchors* at distinct written
     positions (an anchor is an entry whose type has one entry in the map and one instance
     in the layout, so its object is fixed by its type alone: ``Fridge``, ``Television``,
     ``Door`` in every EMRD layout), the seed is the Procrustes fit of the anchors.
   * **Undetermined frame** (fewer than two anchors). The seeds are the motions that carry
     two base entries onto every pair of candidate objects (see
     :func:`pytest_emrd.metrics._seeds.hypotheses`), preceded by the fit of the previous
     step's identities of the labels still present, then by the fit of the labels that are
     object ids of the layout (``Chair_3``). The lowest residual wins; between fits the
     geometry cannot tell apart (one chair left in the map; three chairs of an evenly
     spaced row) the previous identities decide, then the labels.

   Every seed is computed from distances and residuals only, so the result is the same in
   every frame: the matching, and every metric built on it, is **invariant under any proper
   rigid motion** (rotation + translation) of the map, exactly, not approximately (residuals
   and distances are compared at 1e-9 relative precision so ties break alike in every frame;
   remaining exact ties go to the lowest object id). It is also invariant under the order of
   the entries, and under any consistent renaming of the labels except where two
   correspondences fit exactly equally well.

**Reflections are not forgiven.** The paper's alignment is rigid-body: rotation and
translation, ``det R = +1``. A mirrored map (left and right swapped) cannot be rotated onto
the layout; it keeps its residual and Positional Accuracy falls (except for a collinear map,
which a half-turn maps onto its own mirror image). Swapping left and right is a spatial
error a responder must not make, so we do not forgive it by allowing improper alignments.

4. **Identity over time** (episodes: :meth:`Matcher.assign` with the previous step's
   assignment). Objects are followed across steps by label (Appendix B: "matched across time
   steps exclusively using the string labels"). A label keeps the object it held at step
   ``t-1`` only when the identity was decided in a *determined* frame and step ``t`` is
   determined too, by no anchor that ``t-1`` lacked; its type must still resolve to that
   object's type. The other labels are assigned among the remaining objects in step ``t``'s
   anchor frame. Identities are **revised** (decided afresh by step 3) whenever a new anchor
   appears (the frame is better determined than when they were decided) and at every
   undetermined step: an identity decided while the frame was undetermined never persists
   by itself; at an undetermined step the previous identities only break ties the map's
   geometry cannot break (one chair left in the map: still the chair it was). Every rule
   reads labels, types and equivariant fits, so carrying keeps the invariance.

**No distance gate.** A type-correct entry is matched however far it lies from its object:
(a) a gate would have to be set in the model's untrusted frame; (b) the paper's coverage
(Eq. AEC) counts instances per type with a ``min`` cap and no position test, and matching
must agree with it: ``|K| = sum_k min(|M_k|, |E_k|)`` so that AEC is ``|K| / |E|``.
Geometric error is the job of Positional Accuracy, not of the matcher.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Final, NamedTuple

import numpy as np

from pytest_emrd.metrics._align import (
    COINCIDENT_M,
    Motion,
    Problem,
    assign,
    compiled,
    digits,
    layout_of,
    procrustes,
    undetermined_fit,
)
from pytest_emrd.metrics._vocab import TypeResolver
from pytest_emrd.trajectory import GroundTruthObject, MapEntry


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
    """Labels of a ground-truth type beyond that type's instance count (sorted)."""
    unrecognised: tuple[str, ...]
    """Labels whose type resolves to no ground-truth type (sorted)."""
    duplicates: tuple[str, ...]
    """Labels that appeared more than once; only their first entry was used."""
    determined: bool
    """Whether two or more anchors determined the frame (step 3); else correspondence
    hypotheses did."""

    @property
    def object_ids(self) -> frozenset[str]:
        return frozenset(p.object_id for p in self.pairs)

    @property
    def label_of(self) -> dict[str, str]:
        """Object id -> the label matched to it."""
        return {p.object_id: p.label for p in self.pairs}


EMPTY_MATCHING: Final = Matching((), (), (), (), False)

Key = tuple[tuple[str, int, float, float], ...]
"""A map's recognised entries as ``(label, type index, x, z)``, sorted by label."""


def rigid_fit(pred: np.ndarray, true: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Optimal proper rigid motion (rotation + translation) taking ``pred`` onto ``true``.

    2-D orthogonal Procrustes without scaling or reflection (Kabsch with ``det R = +1``):
    the rotation angle maximising ``sum_j q_j . R p_j`` for centred points is
    ``atan2(sum p x q, sum p . q)``. Returns ``(R, t)`` with ``aligned = pred @ R.T + t``.
    Degenerate input (one point, or all points coincident) gives the identity rotation and
    the translation between centroids.
    """
    pred = np.ascontiguousarray(pred, dtype=float).reshape(-1, 2)
    true = np.ascontiguousarray(true, dtype=float).reshape(-1, 2)
    m = procrustes(pred, true, [(i, i) for i in range(len(pred))])
    return np.array([[m.c, -m.s], [m.s, m.c]]), np.array([m.tx, m.tz])


class Assignment(NamedTuple):
    """Raw result of :meth:`Matcher.assign` (plain dicts: the fast path of episodes)."""

    entries: dict[str, MapEntry]
    """Label -> its first entry."""
    identity: dict[str, int]
    """Label -> index (objects sorted by id) of the object matched to it."""
    unmatched: tuple[str, ...]
    unrecognised: tuple[str, ...]
    duplicates: tuple[str, ...]
    determined: bool
    anchors: frozenset[str]
    """Labels of the anchors that determined the frame (empty when undetermined)."""


class Matcher:
    """:func:`match_map` bound to one episode's ground truth, reusable across its steps.

    Holds per-episode look-up tables (the type of each text seen so far) and the result of
    every distinct map already matched afresh.
    """

    def __init__(self, objects: Sequence[GroundTruthObject]) -> None:
        ordered = sorted(objects, key=lambda o: o.object_id)
        self._objects = ordered
        self._types = TypeResolver(o.object_type for o in ordered)
        self._ids = [o.object_id for o in ordered]
        self._index = {oid: c for c, oid in enumerate(self._ids)}
        self._true = np.array([(o.x, o.z) for o in ordered], dtype=float).reshape(-1, 2)
        self._true_kinds = np.array([self._types.index[o.object_type] for o in ordered], dtype=int)
        self._kind_of = self._true_kinds.tolist()
        self._count = np.bincount(self._true_kinds, minlength=len(self._types.names)).tolist()
        self._first = [self._kind_of.index(k) if n else -1 for k, n in enumerate(self._count)]
        self._once = [n == 1 for n in self._count]
        self._layout = layout_of([(o.x, o.z) for o in ordered], self._kind_of, _extent(self._true))
        self._done: dict[Key, tuple[dict[str, int], bool]] = {}

    def assign(self, entries: Sequence[MapEntry], previous: Assignment | None = None) -> Assignment:
        """Steps 1-4 of the procedure on plain dicts (the fast path of episodes).

        ``previous`` is the assignment of the step before (episodes only): when both steps
        are determined by the same anchors, its identities are carried (step 4).
        """
        seen: dict[str, MapEntry] = {}
        for e in entries:
            if e.label not in seen:
                seen[e.label] = e
        duplicates: tuple[str, ...] = ()
        if len(seen) != len(entries):
            counts = Counter(e.label for e in entries)
            duplicates = tuple(sorted(lb for lb, n in counts.items() if n > 1))
        resolve, known = self._types.resolve, self._types.known
        type_of: dict[str, int] = {}
        unrecognised: list[str] = []  # sorted, as the labels are visited
        rows: list[int] = []  # anchor candidates: entries of a type the layout holds once
        key_list: list[tuple[str, int, float, float]] = []
        once = self._once
        for lb in sorted(seen):
            e = seen[lb]
            k = known.get((e.object_type, lb))
            if k is None:
                k = resolve(e.object_type, lb)
            if k < 0:
                unrecognised.append(lb)
                continue
            type_of[lb] = k
            if once[k]:
                rows.append(len(key_list))
            key_list.append((lb, k, float(e.x), float(e.z)))
        key = tuple(key_list)
        # anchors: the only entry of a type the layout holds once
        if len(rows) >= 2:
            kinds = [key[r][1] for r in rows]
            if len(set(kinds)) != len(kinds):
                rows = [r for r, k in zip(rows, kinds, strict=True) if kinds.count(k) == 1]
        determined = len(rows) >= 2 and _apart([key[r][2:] for r in rows])
        anchors = frozenset([key[r][0] for r in rows]) if determined else frozenset()
        if (
            determined
            and previous is not None
            and previous.determined
            and anchors <= previous.anchors
        ):
            kind_of = self._kind_of
            identity = {
                lb: c for lb, c in previous.identity.items()
                if type_of.get(lb, -1) == kind_of[c]
            }  # fmt: skip
            if len(identity) < len(key):
                identity.update(self._in_frame(key, rows, identity))
        else:
            kind_of = self._kind_of
            before = () if determined or previous is None else tuple(sorted(
                (lb, c) for lb, c in previous.identity.items() if type_of.get(lb, -1) == kind_of[c]
            ))  # fmt: skip
            done = self._done.get((key, before))  # seen before (parse failures repeat a map)
            if done is None:
                done = self._afresh(key, rows if determined else None, dict(before))
                self._done[(key, before)] = done
            identity = done[0]
        unmatched = tuple([entry[0] for entry in key if entry[0] not in identity])
        return Assignment(
            seen, identity, unmatched, tuple(unrecognised), duplicates, determined,
            anchors,
        )  # fmt: skip

    def _afresh(
        self, key: Key, anchor_rows: list[int] | None, before: dict[str, int]
    ) -> tuple[dict[str, int], bool]:
        """Step 3: every identity of a map decided from the map (``before``: the identities of
        the previous step, which break ties the map's geometry cannot break)."""
        if not key:
            return {}, False
        if anchor_rows is not None:
            return self._in_frame(key, anchor_rows, {}), True
        written = [(x, z) for _, _, x, z in key]
        problem = Problem(written, [k for _, k, _, _ in key], self._layout)
        index, kind_of = self._index, self._kind_of
        named = [(r, index[lb]) for r, (lb, k, _, _) in enumerate(key)
                 if lb in index and kind_of[index[lb]] == k]  # fmt: skip
        kept = [(r, before[lb]) for r, (lb, _, _, _) in enumerate(key) if lb in before]
        pairs = undetermined_fit(problem, kept, named)
        return {key[r][0]: c for r, c in pairs}, False

    def _in_frame(self, key: Key, anchor_rows: list[int], kept: dict[str, int]) -> dict[str, int]:
        """The labels of ``key`` not in ``kept``, assigned among the objects not kept, in the
        frame the anchors fix (:func:`procrustes` of the anchors onto their objects; both in
        one call, :func:`._seeds.anchored`)."""
        first = self._first
        todo = [r for r, entry in enumerate(key) if entry[0] not in kept]
        flat: list[float] = []
        for r in anchor_rows:
            flat += key[r][2:]
        for r in todo:
            flat += key[r][2:]
        points = np.array(flat)
        points.shape = (len(anchor_rows) + len(todo), 2)
        layout = self._layout
        finite, found, motion = compiled("_seeds").anchored(
            points,
            np.array([first[key[r][1]] for r in anchor_rows], dtype=np.intp),
            np.array([key[r][1] for r in todo], dtype=np.intp),
            np.array(list(kept.values()), dtype=np.intp),
            layout.starts, layout.cols, layout.true, digits(layout.scale, 2),
        )  # fmt: skip
        if finite:
            return {key[todo[i]][0]: c for i, c in enumerate(found.tolist()) if c >= 0}
        problem = Problem(
            [key[r][2:] for r in todo], [key[r][1] for r in todo], layout, tuple(kept.values())
        )  # a distance that is not finite: the matrix path
        return {key[todo[i]][0]: c for i, c in assign(problem, Motion(*motion))}

    def held(self, assignment: Assignment) -> dict[str, str]:
        """Object id -> label of an assignment (what :attr:`Matching.label_of` gives)."""
        ids = self._ids
        return {ids[c]: lb for lb, c in assignment.identity.items()}

    def match(self, entries: Sequence[MapEntry]) -> Matching:
        """Match one cognitive map afresh (see the module docstring)."""
        return self.matching(self.assign(entries))

    def matching(self, a: Assignment) -> Matching:
        """The :class:`Matching` of an assignment."""
        pairs = sorted(
            (
                MatchedPair(
                    label=lb,
                    object_id=self._objects[c].object_id,
                    object_type=self._objects[c].object_type,
                    pred_x=float(a.entries[lb].x),
                    pred_z=float(a.entries[lb].z),
                    true_x=float(self._true[c, 0]),
                    true_z=float(self._true[c, 1]),
                )
                for lb, c in a.identity.items()
            ),
            key=lambda p: p.object_id,
        )
        return Matching(tuple(pairs), a.unmatched, a.unrecognised, a.duplicates, a.determined)


def _extent(xy: np.ndarray) -> float:
    """Largest distance of a point from the centroid (0.0 for no point)."""
    if not len(xy):
        return 0.0
    return float(np.max(np.hypot(*(xy - xy.mean(axis=0)).T)))


def _apart(points: Sequence[tuple[float, float]]) -> bool:
    """Whether some point lies farther than :data:`COINCIDENT_M` from the first (the points do
    not all coincide; rigid-invariant)."""
    p0 = points[0]
    return any(math.dist(p0, p) > COINCIDENT_M for p in points)


def step_matchings(
    steps: Sequence[Sequence[MapEntry]], objects: Sequence[GroundTruthObject]
) -> tuple[Matching, ...]:
    """The matching of every step's map of an episode, as the episode metrics see them
    (identities carried and revised by step 4 of the procedure)."""
    matcher = Matcher(objects)
    out: list[Matching] = []
    previous: Assignment | None = None
    for entries in steps:
        previous = matcher.assign(entries, previous)
        out.append(matcher.matching(previous))
    return tuple(out)


def match_map(entries: Sequence[MapEntry], objects: Sequence[GroundTruthObject]) -> Matching:
    """Match a cognitive map to ground truth: THE procedure of every EMRD metric.

    See the module docstring of :mod:`pytest_emrd.metrics._match` for the steps, why the
    result does not depend on the model's frame, and why no distance gate applies.

    Edge cases: an empty map or an empty ground truth gives no pairs; entries whose type is
    unknown are listed in ``unrecognised``; a single entry and a single object of the same
    type always match; a single entry of a type with several instances takes the first of
    them by id (with one point nothing in the map can tell them apart).
    """
    return Matcher(objects).match(entries)
