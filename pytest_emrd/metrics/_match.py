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
2. **Resolve a type.** The entry's ``object_type`` is tried first, then its label. The text is
   normalised (:func:`type_key`: lower case, ``(...)`` asides removed, separators removed,
   trailing instance suffixes such as ``_2``, ``#3``, `` b`` removed) and looked up among the
   ground-truth types of this episode, then in :data:`SYNONYMS` (first candidate present in the
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
   Entries are ordered by label and objects by id, and costs are rounded to 1e-9 m, so ties
   resolve the same way on every machine.

**No distance gate.** A type-correct entry is matched however far it lies from its object:
(a) coordinates are in an untrusted frame, and a gate in that frame would punish exactly the
frame offsets Procrustes is meant to forgive; (b) the paper's coverage (Eq. AEC) counts
instances per type with a ``min`` cap and no position test, and matching must agree with it:
``|K| = sum_k min(|M_k|, |E_k|)`` so that AEC is ``|K| / |E|``. Geometric error is the job of
Positional Accuracy, not of the matcher.
"""

from __future__ import annotations

import math
import re
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from functools import lru_cache
from typing import Final, NamedTuple

import numpy as np
from scipy.optimize import linear_sum_assignment

from pytest_emrd.trajectory import GroundTruthObject, MapEntry

#: Normalised text -> ground-truth types it may denote, in order of preference.
SYNONYMS: Final[dict[str, tuple[str, ...]]] = {
    "table": ("DiningTable", "CoffeeTable", "SideTable", "Desk"),
    "conferencetable": ("DiningTable",),
    "meetingtable": ("DiningTable",),
    "longtable": ("DiningTable",),
    "receptiondesk": ("Desk",),
    "plant": ("HousePlant",),
    "pottedplant": ("HousePlant",),
    "tv": ("Television",),
    "screen": ("Television",),
    "monitor": ("Television",),
    "fridge": ("Fridge",),
    "refrigerator": ("Fridge",),
    "armchair": ("ArmChair",),
    "sofa": ("Sofa", "ArmChair"),
    "couch": ("Sofa", "ArmChair"),
    "doorway": ("Doorway",),
    "doorframe": ("Doorway",),
    "opening": ("Doorway",),
    "passage": ("Doorway",),
    "exit": ("Door",),
    "exitdoor": ("Door",),
    "frontdoor": ("Door",),
    "counter": ("CounterTop",),
    "kitchencounter": ("CounterTop",),
    "shelf": ("ShelvingUnit", "Shelf"),
    "shelves": ("ShelvingUnit", "Shelf"),
    "bookshelf": ("ShelvingUnit", "Shelf"),
    "coffeemaker": ("CoffeeMachine",),
    "barstool": ("Stool",),
    "computer": ("Laptop",),
    "notebook": ("Laptop",),
}

_ASIDE = re.compile(r"\(.*?\)|\[.*?\]")
_TOKENS = re.compile(r"[a-z0-9]+")
_TRAILING_DIGITS = re.compile(r"\d+$")
_ROUND: Final = 9


@lru_cache(maxsize=4096)
def type_key(text: str) -> str:
    """Normalised comparison key of a type or label: ``"Dining table #2"`` -> ``"diningtable"``.

    Lower-cases, drops ``(...)``/``[...]`` asides, splits on anything that is not a letter or
    digit, drops trailing tokens that are numbers or single letters (instance suffixes), joins
    the rest and strips trailing digits. Empty or suffix-only text gives ``""``.
    """
    tokens = _TOKENS.findall(_ASIDE.sub(" ", text.lower()))
    while len(tokens) > 1 and (tokens[-1].isdigit() or len(tokens[-1]) == 1):
        tokens.pop()
    return _TRAILING_DIGITS.sub("", "".join(tokens))


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


EMPTY_MATCHING: Final = Matching((), (), (), (), False)


def rigid_fit(pred: np.ndarray, true: np.ndarray) -> tuple[np.ndarray, np.ndarray]:
    """Optimal proper rigid motion (rotation + translation) taking ``pred`` onto ``true``.

    2-D orthogonal Procrustes without scaling or reflection (Kabsch with ``det R = +1``):
    the rotation angle maximising ``sum_j q_j . R p_j`` for centred points is
    ``atan2(sum p x q, sum p . q)``. Returns ``(R, t)`` with ``aligned = pred @ R.T + t``.
    Degenerate input (one point, or all points coincident) gives the identity rotation and
    the translation between centroids.
    """
    pc = pred.sum(axis=0) / len(pred)
    qc = true.sum(axis=0) / len(true)
    h = (pred - pc).T @ (true - qc)
    dot = float(h[0, 0] + h[1, 1])
    cross = float(h[0, 1] - h[1, 0])
    theta = math.atan2(cross, dot) if (dot or cross) else 0.0
    c, s = math.cos(theta), math.sin(theta)
    rot = np.array([[c, -s], [s, c]])
    return rot, qc - pc @ rot.T


class Assignment(NamedTuple):
    """Raw result of :meth:`Matcher.assign`: row ``r`` is ``labels[r]`` at ``pred[r]``."""

    labels: list[str]
    """Labels with a recognised type, sorted."""
    pred: np.ndarray
    """``(n, 2)`` positions as written."""
    obj: list[int]
    """Index of the matched object (sorted by id) per row, -1 when unmatched."""
    unrecognised: tuple[str, ...]
    duplicates: tuple[str, ...]
    anchored: bool


class Matcher:
    """:func:`match_map` bound to one episode's ground truth, reusable across its steps.

    Holds only per-episode look-up tables (type resolution of each label seen so far);
    matching one map never depends on previous calls.
    """

    def __init__(self, objects: Sequence[GroundTruthObject]) -> None:
        ordered = sorted(objects, key=lambda o: o.object_id)
        self._objects = ordered
        self._types = sorted({o.object_type for o in ordered})
        index = {t: i for i, t in enumerate(self._types)}
        self._obj_type = np.array([index[o.object_type] for o in ordered], dtype=np.int64)
        self._obj_xy = np.array([(o.x, o.z) for o in ordered], dtype=float).reshape(-1, 2)
        self._type_count = np.bincount(self._obj_type, minlength=len(self._types))
        self._key_to_type: dict[str, int] = {type_key(t): i for t, i in index.items()}
        for key, candidates in SYNONYMS.items():
            if key not in self._key_to_type:
                hit = next((index[c] for c in candidates if c in index), None)
                if hit is not None:
                    self._key_to_type[key] = hit
        self._resolved: dict[tuple[str, str], int] = {}
        self._ids = [o.object_id for o in ordered]
        self._index = {oid: c for c, oid in enumerate(self._ids)}
        self._obj_type_list = self._obj_type.tolist()
        self._all_types = set(range(len(self._types)))
        self._type_count_list = self._type_count.tolist()
        self._singleton_col = np.zeros(len(self._types), dtype=np.int64)
        self._singleton_col[self._obj_type[::-1]] = np.arange(len(ordered))[::-1]

    def resolve(self, object_type: str, label: str) -> int:
        """Ground-truth type index of an entry, or -1 when unrecognised."""
        cache_key = (object_type, label)
        hit = self._resolved.get(cache_key)
        if hit is None:
            hit = self._resolve_text(object_type)
            if hit < 0:
                hit = self._resolve_text(label)
            self._resolved[cache_key] = hit
        return hit

    def _resolve_text(self, text: str) -> int:
        key = type_key(text)
        if not key:
            return -1
        for candidate in (key, key[:-1] if key.endswith("s") else "", key[:-2]):
            if candidate and candidate in self._key_to_type:
                return self._key_to_type[candidate]
        return -1

    def assign(
        self, entries: Sequence[MapEntry], carried: Mapping[str, int] | None = None
    ) -> Assignment:
        """Steps 1-4 of the procedure, as arrays (the fast path of the temporal metrics).

        ``carried`` maps labels to object indices (sorted-by-id order) they kept from the
        previous step: such a label, present again with a type that still resolves to its
        object's type, keeps its object; the other recognised entries are assigned among the
        objects not kept.
        """
        seen: dict[str, MapEntry] = {}
        duplicates: set[str] = set()
        for e in entries:
            if e.label in seen:
                duplicates.add(e.label)
            else:
                seen[e.label] = e
        resolved = self._resolved
        rows: list[str] = []
        row_types: list[int] = []
        unrecognised: list[str] = []
        for lb in sorted(seen):
            e = seen[lb]
            k = resolved.get((e.object_type, lb))
            if k is None:
                k = self.resolve(e.object_type, lb)
            if k < 0:
                unrecognised.append(lb)
            else:
                rows.append(lb)
                row_types.append(k)
        pred = np.array([(seen[lb].x, seen[lb].z) for lb in rows], dtype=float).reshape(-1, 2)
        obj = [-1] * len(rows)
        kept: set[int] = set()
        if carried:
            obj_type = self._obj_type_list
            for r, lb in enumerate(rows):
                c = carried.get(lb, -1)
                if c >= 0 and obj_type[c] == row_types[r]:
                    obj[r] = c
                    kept.add(c)
        free_types = self._free_types(kept)
        todo = [r for r, c in enumerate(obj) if c < 0 and row_types[r] in free_types]
        anchored = False
        if todo:
            types = np.array(row_types, dtype=np.int64)
            aligned, anchored = self._align(pred, types)
            cols = [c for c in range(len(self._ids)) if c not in kept]
            sub = aligned[todo]
            diff = sub[:, None, :] - self._obj_xy[cols][None, :, :]
            cost = np.round(np.sqrt(np.einsum("ijk,ijk->ij", diff, diff)), _ROUND)
            allowed = types[todo][:, None] == self._obj_type[cols][None, :]
            big = (float(cost.max()) + 1.0) * (min(cost.shape) + 1)
            r_idx, c_idx = linear_sum_assignment(np.where(allowed, cost, big))
            for r, c in zip(r_idx.tolist(), c_idx.tolist(), strict=True):
                if allowed[r, c]:
                    obj[todo[r]] = cols[c]
        return Assignment(rows, pred, obj, tuple(unrecognised), tuple(sorted(duplicates)), anchored)

    def _free_types(self, kept: set[int]) -> set[int]:
        if not kept:
            return self._all_types
        used = [0] * len(self._types)
        for c in kept:
            used[self._obj_type_list[c]] += 1
        return {k for k, n in enumerate(self._type_count_list) if n > used[k]}

    def held(self, assignment: Assignment) -> dict[str, str]:
        """Object id -> label of an assignment (what :attr:`Matching.label_of` gives)."""
        ids = self._ids
        return {ids[c]: assignment.labels[r] for r, c in enumerate(assignment.obj) if c >= 0}

    def carry(self, assignment: Assignment) -> dict[str, int]:
        """Label -> object index of the matched rows, to pass as ``carried`` next step."""
        return {assignment.labels[r]: c for r, c in enumerate(assignment.obj) if c >= 0}

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
                    label=a.labels[r],
                    object_id=self._objects[c].object_id,
                    object_type=self._objects[c].object_type,
                    pred_x=float(a.pred[r, 0]),
                    pred_z=float(a.pred[r, 1]),
                    true_x=float(self._obj_xy[c, 0]),
                    true_z=float(self._obj_xy[c, 1]),
                )
                for r, c in enumerate(a.obj)
                if c >= 0
            ),
            key=lambda p: p.object_id,
        )
        unmatched = tuple(lb for lb, c in zip(a.labels, a.obj, strict=True) if c < 0)
        return Matching(tuple(pairs), unmatched, a.unrecognised, a.duplicates, a.anchored)

    def _align(self, pred: np.ndarray, row_types: np.ndarray) -> tuple[np.ndarray, bool]:
        entry_count = np.bincount(row_types, minlength=len(self._types))
        anchor_types = np.flatnonzero((entry_count == 1) & (self._type_count == 1))
        if len(anchor_types) < 2:
            return pred, False
        row_of_type = np.empty(len(self._types), dtype=np.int64)
        row_of_type[row_types] = np.arange(len(row_types))
        anchor_pred = pred[row_of_type[anchor_types]]
        if np.ptp(anchor_pred, axis=0).max() <= 1e-9:
            return pred, False
        rot, shift = rigid_fit(anchor_pred, self._obj_xy[self._singleton_col[anchor_types]])
        return pred @ rot.T + shift, True


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
