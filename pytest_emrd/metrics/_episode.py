"""The per-episode scores (the inner terms of the paper's equations) and their result.

:class:`EpisodeMetrics` holds every EMRD score of one trajectory as plain data, what every
aggregate and gate reads, so an episode's steps are matched once however many metrics are
asked for. "Undefined" is ``None`` together with a reason, never a silent 0.0.
"""

from __future__ import annotations

import math
import statistics
from collections import Counter
from collections.abc import Iterable, Sequence
from dataclasses import asdict, dataclass, field
from functools import cached_property
from typing import Final

import numpy as np

from pytest_emrd._serde import JsonRecord, Schema
from pytest_emrd.metrics._match import (
    COINCIDENT_M,
    MatchedPair,
    Matcher,
    Matching,
    _moved,
    _procrustes,
    _units,
    assign_rows,
    keyed,
    pa_value,
)
from pytest_emrd.metrics._tracking import (
    Spell,
    Track,
    first_spells,
    track_episode,
)
from pytest_emrd.rooms import room_letter
from pytest_emrd.trajectory import CATEGORIES, EpisodeSpec, Trajectory

#: Ground-truth type of doorways (left out of ``O_F`` by FPSG's doorway-free variant).
DOORWAY_TYPE: Final = "Doorway"


def aec_score(matching: Matching, n_objects: int) -> float | None:
    r"""Absolute Environment Coverage of one terminal map (inner term of Eq. AEC).

    .. math::
        AEC^{(i)} = \frac{1}{|E|} \sum_{k \in \mathcal{T}} \min(|M_k^{(i)}|, |E_k|)

    ``|M_k|`` counts distinct labels resolved to type ``k`` (:attr:`Matching.covered` is the
    sum): duplicates and hallucinations never raise the score. As in the paper no position
    enters (PA and precision judge where). A fraction in [0, 1]. Empty map: 0.0 (a real
    zero). ``|E| = 0``: None. Worked example: 3 chairs and a table, a map with 4 chairs and a
    sofa the office lacks: ``(min(4, 3) + 0) / 4 = 0.75``.

    :param matching: The terminal map matched to ground truth (:func:`match_map`).
    :param n_objects: ``|E|``, the objects of the office.
    :returns: ``AEC`` in [0, 1]; 0.0 for an empty map; None when ``|E| = 0``.
    """
    return matching.covered / n_objects if n_objects else None


def te_score(traj: Trajectory) -> int:
    r"""Temporal Efficiency of one episode (inner term of Eq. TE): ``|tau^{(i)}| <= T_max``.

    The number of actions executed before ``Term`` or until the budget ran out. Invalid and
    unparseable actions consume a step and count; the ``Term`` action itself does not. A
    ``Term`` on the first step gives 0; an episode without steps gives 0.

    :param traj: The episode.
    :returns: ``|tau|``, the actions before ``Term`` (0 for none).
    """
    terminal = 1 if traj.status == "terminated" and traj.steps else 0
    return len(traj.steps) - terminal


def positional_accuracy_score(matching: Matching, g_base: int) -> float | None:
    r"""Positional Accuracy of one terminal map (inner term of Eq. PA).

    .. math::
        PA^{(i)} = \exp\!\left(-\frac{RMSE^{(i)}}{L_{gt}^{(i)}}\right) \cdot c^{(i)}

    ``K`` are the matched pairs (:func:`match_map`); their predicted positions are rigidly
    aligned onto ground truth (:func:`rigid_fit`: no scaling, no reflection) and ``RMSE`` is
    the root-mean-square residual. ``L_gt`` is the RMS distance of the *matched* ground-truth
    points from their centroid; ``c`` is :func:`pa_coverage` (over-reporting never pays).
    Result in [0, 1]. Edge cases: ``|K| = 0`` gives 0.0; ``|K| = 1`` aligns perfectly and
    gives ``c``; matched ground truth all at one point gives ``c`` when the residual is 0 and
    0.0 otherwise; ``|G_base| = 0`` gives None. Worked example (Appendix B): 5 discoverable
    objects, 3 mapped exactly: ``exp(0) * 3 / 5 = 0.6``; add 3 entries standing for nothing:
    ``u = 3``, ``c = 0``, PA 0.

    :param matching: The terminal map's :class:`Matching`, pairs and unmatched entries.
    :param g_base: ``|G_base|``, the objects discoverable under the baseline.
    :returns: ``PA`` in [0, 1]; None when ``g_base = 0``.
    """
    if g_base == 0:
        return None
    pred = np.array([(p.pred_x, p.pred_z) for p in matching.pairs], dtype=float)
    true = np.array([(p.true_x, p.true_z) for p in matching.pairs], dtype=float)
    return pa_value(pred.reshape(-1, 2), true.reshape(-1, 2), len(matching.unmatched), g_base)


def precision_score(matching: Matching) -> float | None:
    r"""Map precision of one terminal map: the share of its entries that stand for an object.

    .. math::
        P^{(i)} = \frac{|K^{(i)}|}{|M_T^{(i)}|}

    ``M_T`` are the map's entries, recognised or not, every same-label copy included (a map
    given as a list may repeat a label); ``K`` the entries matched within the gate
    (:func:`match_map`). Copies, entries beyond a type's count or far from every object of
    their type, and hallucinated types all lower it.

    :param matching: The terminal map's :class:`Matching`.
    :returns: ``P`` in [0, 1]; None for an empty map. Worked example: 41 correct entries and
        one "exit sign": ``41 / 42 = 0.976``; 41 correct entries each followed by a copy of
        its label written far from every object of its type: ``41 / 82 = 0.5``.
    """
    return len(matching.pairs) / matching.entries if matching.entries else None


def hallucination_score(matching: Matching) -> float | None:
    r"""Hallucination rate of one terminal map: the share of its entries that stand for no
    object.

    .. math::
        H^{(i)} = \frac{|M_T^{(i)} \setminus K^{(i)}|}{|M_T^{(i)}|} = 1 - P^{(i)}

    ``M_T`` are the map's entries (same-label copies included), ``K`` those matched to an
    object. An entry stands for nothing when its type is one the office does not hold
    (:attr:`Matching.unrecognised`) *or* when it is of a type the office holds and no object
    of that type takes it (:attr:`Matching.unmatched`: an invented instance, beyond the
    type's count or far from every object of its type). So ``H = 1 - P``.

    :param matching: The terminal map's :class:`Matching`, unrecognised entries included.
    :returns: ``H`` in [0, 1]; None for an empty map. Worked example: 40 chairs and desks of
        the office, 2 sofas it lacks and 2 chairs 6 m from every chair: ``4 / 44``; a grid of
        every type over the office is nearly all hallucination.
    """
    return (matching.entries - len(matching.pairs)) / matching.entries if matching.entries else None


def ungrounded_pairs(traj: Trajectory, final: Matching) -> tuple[MatchedPair, ...]:
    r"""The terminal map's matched entries standing for an object the model was never shown
    before it wrote them.

    An entry (a label, or its ``n``-th copy ``label #n``) first appears at the first step
    ``t_e`` whose map holds it; object ``o`` is first shown at the first step ``s_o`` whose
    ``visible_ids`` hold it (the frame showed it legibly). A pair ``(e, o)`` of ``K`` is
    *ungrounded* when ``s_o > t_e`` or ``o`` was never shown: nothing the model saw up to then
    puts ``o`` there, so the entry came from elsewhere (the office's published layout, a
    prompt's inventory, a guess).

    :param traj: The episode: every step's map and ``visible_ids``.
    :param final: The matching of its terminal map (:func:`match_map`).
    :returns: The ungrounded pairs, in ``final.pairs`` order; empty when every pair is grounded.
    """
    first: dict[str, int] = {}
    shown: dict[str, int] = {}
    for t, step in enumerate(traj.steps):
        for key in keyed(step.cognitive_map):
            first.setdefault(key, t)
        for oid in step.visible_ids:
            shown.setdefault(oid, t)
    never = len(traj.steps)
    return tuple(p for p in final.pairs if shown.get(p.object_id, never) > first[p.label])


def grounded_scores(
    traj: Trajectory, final: Matching
) -> tuple[float | None, float | None, dict[str, str]]:
    r"""Grounded coverage and the ungrounded share of one terminal map (ours, beside Eq. AEC).

    .. math::
        AEC_g^{(i)} = \frac{1}{|E|} \sum_{k \in \mathcal{T}} \min(|M_{g,k}^{(i)}|, |E_k|),
        \qquad
        UR^{(i)} = \frac{|K_u^{(i)}|}{|K^{(i)}|}

    ``K`` are the terminal map's matched entries, ``K_u`` the ungrounded ones
    (:func:`ungrounded_pairs`), ``M_{g,k}`` the distinct labels of type ``k`` among ``K \ K_u``:
    the paper's AEC counting only entries matched to an object the frames had shown by the
    step the entry first appeared. ``AEC_g <= AEC``, with equality when every recognised entry
    is matched and grounded. A map of the whole office written after two steps scores
    ``AEC_g`` at most the share of objects those two frames showed, and ``UR`` the share it
    did not see; a model that explores and maps what it sees scores ``UR = 0``.

    :param traj: The episode, read as by :func:`ungrounded_pairs`.
    :param final: The matching of its terminal map.
    :returns: ``(grounded_aec, ungrounded_rate, reasons)``, fractions in [0, 1]:
        ``grounded_aec`` is None when ``|E| = 0``, ``ungrounded_rate`` when no entry is matched
        (``|K| = 0``); ``reasons`` says why for each None.
    """
    reasons: dict[str, str] = {}
    ungrounded = ungrounded_pairs(traj, final)
    rate = len(ungrounded) / len(final.pairs) if final.pairs else None
    if rate is None:
        reasons["ungrounded_rate"] = "no entry of the terminal map is matched (|K| = 0)"
    n_objects = len(traj.ground_truth.objects)
    if not n_objects:
        reasons["grounded_aec"] = "the ground truth lists no object (|E| = 0)"
        return None, rate, reasons
    written = keyed(traj.steps[-1].cognitive_map) if traj.steps else {}
    labels = {(p.object_type, written[p.label].label) for p in final.pairs if p not in ungrounded}
    return len(labels) / n_objects, rate, reasons


@dataclass(frozen=True)
class Grounding:
    """Decide-phase scores of one episode (Appendix B, FPSG), as in :class:`EpisodeMetrics`."""

    fpsg_local: float | None
    fpsg_global: float | None
    never_visited: bool | None
    any_bias: bool | None
    reasons: dict[str, str]
    fpsg_local_ex_doorways: float | None = None
    fpsg_global_ex_doorways: float | None = None


def grounding_scores(traj: Trajectory, final: Matching) -> Grounding:
    r"""Focal-Point Spatial Grounding, Never-Visited and Any-Bias of one episode.

    .. math::
        FPSG^{(i)} = \frac{|\hat{M}_F \cap \mathcal{O}_F|}{|N_{base}|},\qquad
        FPSG_{local}^{(i)} = \frac{|\hat{M}_F \cap \mathcal{O}_F|}{|\mathcal{O}_F|}

    ``F`` is the chosen room, ``O_F`` every ground-truth object filed under ``F`` (the
    paper's definition, doorways included; a doorway is filed under the first of its two
    rooms), ``N_base`` the objects the engine showed the agent at any step (union of
    ``visible_ids``). The intersection counts objects of ``O_F`` the final map matches *and*
    the engine confirmed as seen, so an entry copied from the prompt's inventory is no
    evidence. Fractions in [0, 1]. **Doorway-free variant** (``*_ex_doorways``, ours): a
    doorway is seen from either side and says nothing about its room, so it leaves doorways
    out of ``O_F``. ``never_visited``: ``F`` is not among the rooms the agent stood in.
    ``any_bias``: the final map holds no confirmed object of ``O_F``. Edge cases: no chosen
    room (no ``Term``, or a name that resolves to none) makes all of them None; ``|O_F| = 0``
    makes the local scores None; ``|N_base| = 0`` the global ones.

    :param traj: The episode: its ``Term`` room, the rooms it stood in and ``visible_ids``.
    :param final: The terminal map's matching, whose pairs are the candidate evidence.
    :returns: A :class:`Grounding` with the six scores, each None as the edge cases say.
    """
    room = traj.chosen_room
    if room is None:
        why = "no chosen room (no Term, or a room name that resolves to no room)"
        keys = ("fpsg_local", "fpsg_global", "never_visited", "any_bias")
        return Grounding(None, None, None, None, dict.fromkeys(keys, why))
    in_room = {o.object_id for o in traj.ground_truth.objects if o.room == room}
    doorways = {o.object_id for o in traj.ground_truth.objects if o.object_type == DOORWAY_TYPE}
    observed = {oid for s in traj.steps for oid in s.visible_ids}
    confirmed = final.object_ids & observed
    reasons: dict[str, str] = {}

    def scores(objects: set[str]) -> tuple[float | None, float | None, int]:
        grounded = len(confirmed & objects)
        local = grounded / len(objects) if objects else None
        return local, (grounded / len(observed) if observed else None), grounded

    local, glob, grounded = scores(in_room)
    local_ex, glob_ex, _ = scores(in_room - doorways)
    if local is None:
        reasons["fpsg_local"] = f"chosen room {room!r} holds no ground-truth object"
    if glob is None:
        reasons["fpsg_global"] = "the engine showed the agent no object (|N_base| = 0)"
    return Grounding(
        local, glob, room not in traj.rooms_visited, grounded == 0, reasons, local_ex, glob_ex
    )


def sir_score(traj: Trajectory, track: Track, aec: float | None) -> tuple[float | None, str]:
    r"""Coverage-anchored Spatial Identity Resolution of one episode (Appendix B).

    .. math::
        SIR = AEC \cdot \frac{|M_{first}^{(r)} \cap M_{return}^{(r)}|}{|M_{first}^{(r)}|}

    ``M_first`` are the objects of room ``r`` held at the end of the first visit to ``r``.
    One of them is in ``M_return`` ("actively recognised and successfully deduplicated upon
    re-entering room r") when, at the end of the first re-entry into ``r``, the label it had
    is still in the map, held by an object of ``r`` (which one may differ: identities are
    revised as the frame becomes better determined, a revision of the metric's, not the
    model's), and no entry written during the re-entry is a copy of it
    (:func:`reentry_copies`). The ratio is averaged over every re-entered room with a
    non-empty ``M_first`` and multiplied by the episode's AEC. Returns ``(value, "")`` or
    ``(None, reason)``: no room re-entered, nothing of a re-entered room mapped on the first
    visit, or AEC undefined. Invariant under rigid motions of the map.

    :param traj: The episode, for the rooms the agent stood in step by step.
    :param track: What the temporal metrics read from it: the label held per object and step.
    :param aec: The episode's AEC, the anchor (:func:`aec_score`).
    :returns: ``(SIR, "")`` with SIR in [0, 1], or ``(None, reason)``.
    """
    room_of = {o.object_id: o.room for o in traj.ground_truth.objects}
    held = track.held
    ratios: list[float] = []
    reentered = [v for v in track.visits if v.return_end is not None]
    for v in reentered:
        first = {o: lb for o, lb in held[v.first_end].items() if room_of[o] == v.room}
        if first and v.return_end is not None and v.return_start is not None:
            room_by_label = {lb: room_of[o] for o, lb in held[v.return_end].items()}
            copies = reentry_copies(traj, track.matcher, held, v.return_start, v.return_end)
            kept = sum(
                room_by_label.get(lb) == v.room and o not in copies for o, lb in first.items()
            )
            ratios.append(kept / len(first))
    if not reentered:
        return None, "no room was re-entered"
    if not ratios:
        return None, "no object of a re-entered room was mapped on its first visit"
    if aec is None:
        return None, "AEC is undefined (no ground-truth objects)"
    return aec * float(np.mean(ratios)), ""


def reentry_copies(
    traj: Trajectory, matcher: Matcher, held: Sequence[dict[str, str]], start: int, end: int
) -> frozenset[str]:
    """Objects that an entry written during a re-entry (steps ``start..end``) copies.

    A *new* entry's label is in ``M_end`` but not in the map of the step before ``start``.
    In the alignment of ``M_end`` (:func:`rigid_fit` of every matched entry onto its object)
    the new entries of each type are paired one to one with the objects of that type at the
    least total squared distance (:func:`~._match.assign_rows`, distances rounded to
    ``TIE_M2``; entries beyond the type's count take their nearest object, the first by id on
    ties): the object each *means*. A new entry copies ``o`` when it means ``o`` and another
    label holds ``o``. Unrecognised entries copy nothing. Edge case: fewer than two matched
    entries at distinct positions leave the rotation undetermined: no copy is found.
    """
    entries = keyed(traj.steps[end].cognitive_map)
    before = keyed(traj.steps[start - 1].cognitive_map)  # a re-entry never starts at step 0
    by_type: dict[int, list[str]] = {}
    for lb in sorted(entries.keys() - before):
        k = matcher.types.resolve(entries[lb].object_type, entries[lb].label)
        if k >= 0:
            by_type.setdefault(k, []).append(lb)
    label_of = held[end]
    if not by_type or len(label_of) < 2:
        return frozenset()
    pairs = sorted(label_of.items())
    pred = np.array([(entries[lb].x, entries[lb].z) for _, lb in pairs], dtype=float)
    if np.ptp(pred, axis=0).max() <= COINCIDENT_M:
        return frozenset()
    layout = matcher._layout
    motion = _procrustes(pred, layout.true[[matcher._index[o] for o, _ in pairs]])
    copies: set[str] = set()
    for k, labels in by_type.items():
        cols = np.flatnonzero(layout.kinds == k)
        new = np.array([(entries[lb].x, entries[lb].z) for lb in labels], dtype=float)
        diff = _moved(new, motion)[:, None, :] - layout.true[cols][None, :, :]
        cost = _units(np.sum(diff * diff, axis=2))
        if not np.isfinite(cost).all():
            raise ValueError(f"a written coordinate of {labels} is not finite")
        meant = cols[cost.argmin(axis=1)]
        for r, j in assign_rows(cost, np.ones_like(cost, dtype=bool)):
            meant[r] = cols[j]
        for lb, c in zip(labels, meant.tolist(), strict=True):
            oid = matcher.objects[c].object_id
            if label_of.get(oid, lb) != lb:  # another label holds it
                copies.add(oid)
    return frozenset(copies)


def discovery_thirds(n: int) -> np.ndarray:
    """Discovery third (0 Early, 1 Middle, 2 Late) of ranks ``1..n``, at index ``rank - 1``.

    Three consecutive bins whose sizes differ by at most one, larger bins first
    (``numpy.array_split``: 30 -> 10/10/10, 10 -> 4/3/3, 2 -> 1/1/0).

    :param n: The number of discovered objects.
    :returns: An int array of length ``n`` holding 0, 1 or 2 per rank.
    """
    return np.repeat(np.arange(3), [len(b) for b in np.array_split(np.arange(n), 3)])


def serial_position_bins(
    ttf_by_rank: Sequence[float | None],
) -> tuple[float | None, float | None, float | None]:
    r"""Early / Middle / Late mean time-to-forget of one episode (inner term of Eq. SPE).

    .. math::
        \overline{TTF}_b^{(i)} = \frac{1}{|\mathcal{D}_b^{(i)}|}
            \sum_{j \in \mathcal{D}_b^{(i)}} TTF_j^{(i)}

    ``ttf_by_rank[j]`` is the TTF of the object of discovery rank ``j + 1`` (None when it never
    left view while mapped). Ranks are split into thirds by :func:`discovery_thirds`. A bin's
    mean is over its objects with a TTF; a bin with none, or no bin at all (fewer than three
    discovered objects leave later bins empty), gives None for that bin.

    :param ttf_by_rank: TTF per discovery rank, None where the object never left view.
    :returns: ``(early, middle, late)`` mean TTF in steps, each None when its bin has no TTF.
    """
    third = discovery_thirds(len(ttf_by_rank))
    bins = (
        [v for v, t in zip(ttf_by_rank, third, strict=True) if t == b and v is not None]
        for b in range(3)
    )
    early, middle, late = (statistics.fmean(values) if values else None for values in bins)
    return early, middle, late


SCHEMA_VERSION: Final = 3


@dataclass(frozen=True, kw_only=True)
class EpisodeMetrics(JsonRecord):
    """Every per-episode EMRD score of one trajectory. Fractions are in [0, 1]. A score's
    default is its value for an errored episode: none."""

    schema = Schema(
        SCHEMA_VERSION,
        "episode metrics",
        "recompute them from the trajectory with episode_metrics().",
    )

    spec: EpisodeSpec
    status: str
    """Trajectory status: ``terminated``, ``budget`` or ``errored``."""
    errored: bool
    """Errored episodes carry no scores; aggregates exclude and count them."""
    steps: int
    """Decision cycles recorded."""
    parse_failures: int
    """Steps whose reply could not be read."""
    te: int | None = None
    """Temporal Efficiency: actions before ``Term`` or the budget (Eq. TE)."""
    aec: float | None = None
    """Absolute Environment Coverage of the terminal map (Eq. AEC)."""
    pa: float | None = None
    """Positional Accuracy of the terminal map (Eq. PA)."""
    matched: int = 0
    """``|K|``: terminal-map entries matched to ground truth."""
    g_base: int
    """``|G_base|``: objects discoverable under the unperturbed baseline."""
    unmatched: int = 0
    """``|U|``: recognised terminal-map entries left without an object (PA's charge)."""
    precision: float | None = None
    """Map precision: share of the terminal map's entries standing for a real object."""
    hallucination_rate: float | None = None
    """Share of the terminal map's entries that stand for no object (``1 - precision``)."""
    grounded_aec: float | None = None
    """AEC over entries matched to an object shown by the step they first appeared."""
    ungrounded_rate: float | None = None
    """Share of the terminal map's matched entries whose object was not shown by then."""
    tbs: tuple[float, ...] = ()
    """Temporal Belief Stability ``TBS(t)`` for ``t = 1..steps`` (Eq. TBS)."""
    fpsg_local: float | None = None
    fpsg_global: float | None = None
    never_visited: bool | None = None
    """The chosen room is one the agent never stood in (None: no chosen room)."""
    any_bias: bool | None = None
    """The final map holds no confirmed object of the chosen room (None: no chosen room)."""
    chosen_letter: str
    """Focal-point column: ``C``, ``O``, ``K``, ``E`` or ``X`` (anything else, incl. no Term)."""
    sir: float | None = None
    """Spatial Identity Resolution (None when no room was re-entered; see ``reasons``)."""
    spells: tuple[Spell, ...] = ()
    """Every out-of-view spell of every mapped object, in start order."""
    mapped_by_category: dict[str, int] = field(default_factory=dict)
    """Objects ever held in the map, per memory category (coverage numerator ``C_X``)."""
    objects_by_category: dict[str, int]
    """Ground-truth objects per memory category (coverage denominator ``C_X``)."""
    serial_position: tuple[float | None, float | None, float | None] = (None, None, None)
    """Mean TTF of the Early / Middle / Late discovery thirds (Eq. SPE)."""
    miller_loads: tuple[int, ...] = ()
    """Map size ``m = |M_{t-1}|`` for each step ``t >= 2`` with ``m >= 1``."""
    miller_forgets: tuple[bool, ...] = ()
    """Forgetting indicator of those steps (Eq. MillerLaw)."""
    rationale: str | None = None
    """The terminal reasoning, for representative-reasoning analysis."""
    reasons: dict[str, str] = field(default_factory=dict)
    """Metric name -> why it is None (or, for ``memory_strength``, unbounded)."""
    fpsg_local_ex_doorways: float | None = None
    """``fpsg_local`` with doorways left out of ``O_F`` (our variant, reported beside)."""
    fpsg_global_ex_doorways: float | None = None
    """``fpsg_global`` with doorways left out of ``O_F``."""
    schema_version: int = SCHEMA_VERSION

    @cached_property
    def ttf_spells(self) -> tuple[Spell, ...]:
        """The first spell of each object: its time-to-forget, in discovery order."""
        return first_spells(self.spells)

    @property
    def forget_events(self) -> int:
        """``d``: uncensored forgetting events among ``ttf_spells``."""
        return sum(s.forgotten for s in self.ttf_spells)

    @property
    def retained_steps(self) -> int:
        """``sum t_j`` over ``ttf_spells`` (events and censored alike)."""
        return sum(s.duration for s in self.ttf_spells)

    @property
    def memory_strength(self) -> float | None:
        """Per-episode EFC ``sum t_j / d`` (Eq. SMLE): ``inf`` when ``d = 0`` with spells,
        None without spells or for an errored episode."""
        if self.errored or not self.spells:
            return None
        d = self.forget_events
        return self.retained_steps / d if d else math.inf


#: The scores an errored episode leaves undefined (its ``reasons`` say why for each).
_UNDEFINED_WHEN_ERRORED: Final = (
    "te",
    "aec",
    "pa",
    "precision",
    "hallucination_rate",
    "grounded_aec",
    "ungrounded_rate",
    "tbs",
    "fpsg_local",
    "fpsg_global",
    "never_visited",
    "any_bias",
    "sir",
    "memory_strength",
)


def episode_metrics(traj: Trajectory) -> EpisodeMetrics:
    """Compute every per-episode score of ``traj`` (one pass over its steps).

    :param traj: The episode, errored or not.
    :returns: Its :class:`EpisodeMetrics`: every per-episode score, with reasons for the None ones.
    """
    g_base = len(traj.ground_truth.discoverable_ids)
    common = {
        "spec": traj.spec,
        "status": traj.status,
        "steps": len(traj.steps),
        "parse_failures": sum(s.parse_error is not None for s in traj.steps),
        "g_base": g_base,
        "objects_by_category": dict(Counter(o.category for o in traj.ground_truth.objects)),
        "rationale": traj.rationale,
    }
    if traj.status == "errored":
        why = f"episode errored: {traj.error or 'no cause recorded'}"
        return EpisodeMetrics(
            **common,
            errored=True,
            chosen_letter=room_letter(None),
            reasons=dict.fromkeys(_UNDEFINED_WHEN_ERRORED, why),
        )
    track = track_episode(traj)
    final = track.final
    reasons: dict[str, str] = {}
    aec = aec_score(final, len(traj.ground_truth.objects))
    no_base = "no object is discoverable under the baseline (|G_base| = 0)"
    if aec is None:
        reasons["aec"] = "the ground truth lists no object (|E| = 0)"
    if g_base == 0:
        reasons["pa"] = no_base
    grounded_aec, ungrounded_rate, why_ungrounded = grounded_scores(traj, final)
    reasons.update(why_ungrounded)
    if not final.entries:
        reasons["precision"] = reasons["hallucination_rate"] = "the terminal map is empty"
    if g_base == 0:
        reasons["tbs"] = no_base
    grounding = asdict(grounding_scores(traj, final))  # fields of EpisodeMetrics
    reasons.update(grounding.pop("reasons"))
    sir, why = sir_score(traj, track, aec)
    if sir is None:
        reasons["sir"] = why
    first = first_spells(track.spells)
    if not first:
        reasons["memory_strength"] = "no mapped object ever left view"
    elif not any(s.forgotten for s in first):
        reasons["memory_strength"] = "no forgetting event: memory strength is unbounded"
    category = {o.object_id: o.category for o in traj.ground_truth.objects}
    ttf = {s.object_id: float(s.duration) for s in first}
    by_rank = sorted(track.discovery, key=track.discovery.__getitem__)
    return EpisodeMetrics(
        **common,
        errored=False,
        te=te_score(traj),
        aec=aec,
        pa=positional_accuracy_score(final, g_base),
        matched=len(final.pairs),
        unmatched=len(final.unmatched),
        precision=precision_score(final),
        hallucination_rate=hallucination_score(final),
        grounded_aec=grounded_aec,
        ungrounded_rate=ungrounded_rate,
        tbs=track.tbs,
        **grounding,
        chosen_letter=room_letter(traj.chosen_room),
        sir=sir,
        spells=track.spells,
        mapped_by_category=dict(Counter(category[o] for o in track.discovery)),
        serial_position=serial_position_bins([ttf.get(o) for o in by_rank]),
        miller_loads=track.miller_loads,
        miller_forgets=track.miller_forgets,
        reasons=reasons,
    )


EpisodeLike = Trajectory | EpisodeMetrics


def as_episode_metrics(items: Iterable[EpisodeLike]) -> list[EpisodeMetrics]:
    """Episode metrics of each item: computed for a trajectory, passed through otherwise.

    :param items: Trajectories, :class:`EpisodeMetrics`, or a mix.
    :returns: One :class:`EpisodeMetrics` per item, in input order.
    """
    return [i if isinstance(i, EpisodeMetrics) else episode_metrics(i) for i in items]


def split_errored(items: Iterable[EpisodeLike]) -> tuple[list[EpisodeMetrics], int]:
    """The non-errored episode metrics, and how many errored episodes were excluded."""
    all_metrics = as_episode_metrics(items)
    kept = [m for m in all_metrics if not m.errored]
    return kept, len(all_metrics) - len(kept)


def categories_of(metrics: Sequence[EpisodeMetrics]) -> list[str]:
    """Memory categories present, the standard three first, then any other, sorted."""
    seen = {c for m in metrics for c in m.objects_by_category}
    return [c for c in CATEGORIES if c in seen] + sorted(seen - set(CATEGORIES))
