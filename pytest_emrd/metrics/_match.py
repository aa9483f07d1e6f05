"""Label-to-ground-truth matching: the one procedure every metric uses.

A model writes its cognitive map as ``{label: {type, x, z, room}}`` with labels and types of
its own choosing and coordinates in a frame it was told about but may not honour. Every
metric that needs to know *which physical object* a map entry stands for calls
:func:`match_map`, which runs these steps, in this order, deterministically:

0. **Carry identities** (episodes only; see :func:`match_map`'s ``carried``). A label that
   kept an object at the previous step keeps it while its type still resolves to that
   object's type. Steps 3-4 then assign the remaining entries among the remaining objects.
1. **Deduplicate labels.** A label is one recorded instance; a repeated label keeps its first
   entry (the JSON map is keyed by label, so repeats only come from malformed input).
2. **Resolve a type** (:mod:`pytest_emrd.metrics._vocab`). The entry's ``object_type`` is
   tried first, then its label. The text is normalised (``type_key``: lower case, ``(...)``
   asides removed, separators removed, trailing instance suffixes such as ``_2``, ``#3``,
   `` b`` removed) and looked up among the
   ground-truth types of this episode, then in ``SYNONYMS`` (first candidate present in the
   ground truth wins, so ``table`` is a ``DiningTable`` where the layout has one and a ``Desk``
   where it has no table), then without a plural ``s``. Text that resolves to no ground-truth
   type leaves the entry *unrecognised*.
3. **Align on anchors.** Types with exactly one ground-truth instance and exactly one entry are
   unambiguous anchors. With two or more anchors at distinct predicted positions, the map is
   rigidly aligned (rotation + translation, :func:`rigid_fit`) onto the anchors' ground truth
   before step 4; otherwise the model's coordinates are used as written (nominally the spawn
   frame). The assignment is therefore invariant under any rigid motion of the predicted map
   whenever two anchors exist (every EMRD layout has singleton types: Fridge, Television,
   Door, ...), which is what lets Positional Accuracy forgive an arbitrary model frame.
4. **Assign per type.** For each type, the optimal one-to-one assignment
   (:func:`scipy.optimize.linear_sum_assignment`) between its entries and its ground-truth
   instances minimises the summed Euclidean distance in the aligned frame; exactly
   ``min(|M_k|, |E_k|)`` pairs are formed. Entries beyond the instance count stay *unmatched*.
   A single entry takes the nearest free instance (ties: lowest object id); entries are
   ordered by label and objects by id, and costs are rounded to 1e-9 m, so ties resolve the
   same way on every machine.

**No distance gate.** A type-correct entry is matched however far it lies from its object:
(a) coordinates are in an untrusted frame, and a gate in that frame would punish exactly the
frame offsets Procrustes is meant to forgive; (b) the paper's coverage (Eq. AEC) counts
instances per type with a ``min`` cap and no position test, and matching must agree with it:
``|K| = sum_k min(|M_k|, |E_k|)`` so that AEC is ``|K| / |E|``. Geometric error is the job of
Positional Accuracy, not of the matcher.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Final, NamedTuple

import numpy as np

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
    anchored: bool
    """Whether the anchor alignment of step 3 was applied before assigning."""

    @property
    def object_ids(self) -> frozenset[str]:
        return frozenset(p.object_id for p in self.pairs)

    @property
    def label_of(self) -> dict[str, str]:
        """Object id -> the label matched to it."""
        return {p.object_id: p.label for p in self.pairs}


_ROUND: Final = 9
"""Decimals (metres) costs are rounded to, so ties break the same way on every machine."""

EMPTY_MATCHING: Final = Matching((), (), (), (), False)


def _rigid(
    pred: Sequence[tuple[float, float]], true: Sequence[tuple[float, float]]
) -> tuple[float, float, float, float]:
    """``(cos, sin, tx, tz)`` of the optimal proper rigid motion (see :func:`rigid_fit`)."""
    n = len(pred)
    pcx = math.fsum(p[0] for p in pred) / n
    pcz = math.fsum(p[1] for p in pred) / n
    qcx = math.fsum(q[0] for q in true) / n
    qcz = math.fsum(q[1] for q in true) / n
    dot = cross = 0.0
    for (px, pz), (qx, qz) in zip(pred, true, strict=True):
        ax, az, bx, bz = px - pcx, pz - pcz, qx - qcx, qz - qcz
        dot += ax * bx + az * bz
        cross += ax * bz - az * bx
    theta = math.atan2(cross, dot) if (dot or cross) else 0.0
    c, s = math.cos(theta), math.sin(theta)
    return c, s, qcx - (c * pcx - s * pcz), qcz - (s * pcx + c * pcz)


def rigid_fit(pred: np.ndarray, true: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Optimal proper rigid motion (rotation + translation) taking ``pred`` onto ``true``.

    2-D orthogonal Procrustes without scaling or reflection (Kabsch with ``det R = +1``):
    the rotation angle maximising ``sum_j q_j . R p_j`` for centred points is
    ``atan2(sum p x q, sum p . q)``. Returns ``(R, t)`` with ``aligned = pred @ R.T + t``.
    Degenerate input (one point, or all points coincident) gives the identity rotation and
    the translation between centroids.
    """
    c, s, tx, tz = _rigid(
        [(p[0], p[1]) for p in np.asarray(pred, dtype=float).tolist()],
        [(q[0], q[1]) for q in np.asarray(true, dtype=float).tolist()],
    )
    return np.array([[c, -s], [s, c]]), np.array([tx, tz])


class Assignment(NamedTuple):
    """Raw result of :meth:`Matcher.assign` (plain dicts: the fast path of episodes)."""

    entries: dict[str, MapEntry]
    """Label -> its first entry."""
    identity: dict[str, int]
    """Label -> index (objects sorted by id) of the object matched to it."""
    unmatched: tuple[str, ...]
    unrecognised: tuple[str, ...]
    duplicates: tuple[str, ...]
    anchored: bool


class Matcher:
    """:func:`match_map` bound to one episode's ground truth, reusable across its steps.

    Holds only per-episode look-up tables (type resolution of each text seen so far);
    matching one map never depends on previous calls except through ``carried``.
    """

    def __init__(self, objects: Sequence[GroundTruthObject]) -> None:
        ordered = sorted(objects, key=lambda o: o.object_id)
        self._objects = ordered
        self._types = TypeResolver(o.object_type for o in ordered)
        self._ids = [o.object_id for o in ordered]
        self._index = {oid: c for c, oid in enumerate(self._ids)}
        self._obj_type_list = [self._types.index[o.object_type] for o in ordered]
        self._xy = [(o.x, o.z) for o in ordered]
        self._cols_of_type: list[list[int]] = [[] for _ in self._types.names]
        for c, k in enumerate(self._obj_type_list):
            self._cols_of_type[k].append(c)
        self._singleton_col = [cols[0] if len(cols) == 1 else -1 for cols in self._cols_of_type]

    def assign(
        self, entries: Sequence[MapEntry], carried: Mapping[str, int] | None = None
    ) -> Assignment:
        """Steps 0-4 of the procedure on plain dicts (the fast path of episodes).

        ``carried`` maps labels to object indices (sorted-by-id order) they kept from the
        previous step: such a label, present again with a type that still resolves to its
        object's type, keeps its object; the other recognised entries are assigned among the
        objects not kept.
        """
        seen: dict[str, MapEntry] = {}
        identity: dict[str, int] = {}
        todo: dict[int, list[str]] = {}
        type_of: dict[str, int] = {}
        unrecognised: list[str] = []
        known = self._types.known
        resolve = self._types.resolve
        obj_type = self._obj_type_list
        carried = carried or {}
        for e in entries:
            lb = e.label
            if lb in seen:
                continue
            seen[lb] = e
            k = known.get((e.object_type, lb))
            if k is None:
                k = resolve(e.object_type, lb)
            if k < 0:
                unrecognised.append(lb)
                continue
            type_of[lb] = k
            c = carried.get(lb, -1)
            if c >= 0 and obj_type[c] == k:
                identity[lb] = c
            else:
                todo.setdefault(k, []).append(lb)
        duplicates: tuple[str, ...] = ()
        if len(seen) != len(entries):
            counts = Counter(e.label for e in entries)
            duplicates = tuple(sorted(lb for lb, n in counts.items() if n > 1))
        kept = set(identity.values())
        hard: list[tuple[list[str], list[int]]] = []
        for k, labels in todo.items():
            free = [c for c in self._cols_of_type[k] if c not in kept]
            if len(free) == 1 and len(labels) == 1:
                identity[labels[0]] = free[0]
            elif free:
                hard.append((labels, free))
        anchored = False
        if hard:
            anchored = self._assign_by_position(seen, type_of, hard, identity)
        unmatched = tuple(sorted(lb for lb in type_of if lb not in identity))
        return Assignment(
            seen, identity, unmatched, tuple(sorted(unrecognised)), duplicates, anchored
        )

    def _assign_by_position(
        self,
        seen: dict[str, MapEntry],
        type_of: dict[str, int],
        hard: list[tuple[list[str], list[int]]],
        identity: dict[str, int],
    ) -> bool:
        """Steps 3-4 for the types whose assignment is not forced; fills ``identity``.

        Per type: one label takes the nearest free object (ties: lowest object id); several
        labels go through :func:`linear_sum_assignment` on the (label, object) distances.
        """
        from scipy.optimize import linear_sum_assignment  # heavy: imported on first use

        motion = self._align(seen, type_of)
        c, s, tx, tz = motion if motion is not None else (1.0, 0.0, 0.0, 0.0)
        xy = self._xy
        for labels, free in hard:
            points = [
                (c * seen[lb].x - s * seen[lb].z + tx, s * seen[lb].x + c * seen[lb].z + tz)
                for lb in sorted(labels)
            ]
            if len(points) == 1:
                px, pz = points[0]
                best = min(free, key=lambda o: (round(math.hypot(xy[o][0] - px, xy[o][1] - pz),
                                                      _ROUND), o))  # fmt: skip
                identity[labels[0]] = best
                continue
            cost = np.round(
                np.hypot(
                    np.subtract.outer([p[0] for p in points], [xy[o][0] for o in free]),
                    np.subtract.outer([p[1] for p in points], [xy[o][1] for o in free]),
                ),
                _ROUND,
            )
            ordered = sorted(labels)
            for r, col in zip(*linear_sum_assignment(cost), strict=True):
                identity[ordered[int(r)]] = free[int(col)]
        return motion is not None

    def held(self, assignment: Assignment) -> dict[str, str]:
        """Object id -> label of an assignment (what :attr:`Matching.label_of` gives)."""
        ids = self._ids
        return {ids[c]: lb for lb, c in assignment.identity.items()}

    def match(
        self, entries: Sequence[MapEntry], carried: Mapping[str, str] | None = None
    ) -> Matching:
        """Match one cognitive map (see the module docstring)."""
        index = self._index
        kept = {lb: index[oid] for lb, oid in (carried or {}).items() if oid in index}
        return self.matching(self.assign(entries, kept))

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
                    true_x=self._xy[c][0],
                    true_z=self._xy[c][1],
                )
                for lb, c in a.identity.items()
            ),
            key=lambda p: p.object_id,
        )
        return Matching(tuple(pairs), a.unmatched, a.unrecognised, a.duplicates, a.anchored)

    def _align(
        self, seen: dict[str, MapEntry], type_of: dict[str, int]
    ) -> tuple[float, float, float, float] | None:
        """Step 3: the anchor alignment, or None when fewer than two distinct anchors."""
        singleton = self._singleton_col
        candidates = [(lb, singleton[k]) for lb, k in type_of.items() if singleton[k] >= 0]
        counts = Counter(c for _, c in candidates)
        anchors = sorted((lb, c) for lb, c in candidates if counts[c] == 1)
        if len(anchors) < 2:
            return None
        pred = [(seen[lb].x, seen[lb].z) for lb, _ in anchors]
        xs = [p[0] for p in pred]
        zs = [p[1] for p in pred]
        if max(max(xs) - min(xs), max(zs) - min(zs)) <= 1e-9:
            return None
        return _rigid(pred, [self._xy[c] for _, c in anchors])


def match_map(
    entries: Sequence[MapEntry],
    objects: Sequence[GroundTruthObject],
    *,
    carried: Mapping[str, str] | None = None,
) -> Matching:
    """Match a cognitive map to ground truth: THE procedure of every EMRD metric.

    See the module docstring of :mod:`pytest_emrd.metrics._match` for the steps and why no
    distance gate applies. ``carried`` (label -> object id) is the identity each label held at
    the previous step: a label still present with a type of its object's type keeps it (step
    0), and only the other entries are assigned, among the objects not kept. Episodes apply
    the procedure step by step this way, so a label is one object for as long as it stays in
    the map (the paper tracks objects across steps by label, Appendix B).

    Edge cases: an empty map or an empty ground truth gives no pairs; entries whose type is
    unknown are listed in ``unrecognised``; a single entry and a single object of the same type
    always match; a carried id absent from ``objects`` is ignored.
    """
    return Matcher(objects).match(entries, carried)
