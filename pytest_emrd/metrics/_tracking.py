"""One pass over an episode's steps: what the map holds, when, and for how long.

Every temporal metric (TBS, spells and time-to-forget, Kaplan-Meier, Ebbinghaus, serial
position, Miller's law, SIR) reads the :class:`Track` built here. Step ``t`` is 1-based
(:mod:`pytest_emrd.trajectory` has the timeline); the docs page "Map and memory metrics a
model cannot fool" gives the reason and measured effect of each choice:

* ``held(o, t)``: the matching of ``M_t`` (:meth:`._match.Matcher.step`) pairs one of its
  entries with object ``o``; that entry's label is ``o``'s *holder* at ``t``. The terminal
  scores use :func:`._match.match_map` of the terminal map alone. ``in_view(o, t)``: ``o`` is
  in ``visible_ids``.
* **Spell**: starts at step ``s`` when ``o`` was in view and held at ``s-1`` and is out of
  view at ``s``; it follows the holder ``l`` at ``s-1``. The first out-of-view step ``t`` at
  which ``l`` is gone from ``M_t``, or relabelled away (its type no longer resolves to
  ``o``'s), is a *forgetting event* of duration ``t - s + 1`` (the paper's KM example counts
  ``tau = 1`` as the first step after leaving view). The spell is *right-censored* at
  ``t - s`` when ``o`` comes back into view at ``t`` with ``l`` still written, and at
  ``T - s + 1`` when the episode ends at ``T``. An object mapped out of view opens no spell.
* **Discovery** of ``o``: the step at which the model wrote, as it still stands, an entry
  whose label holds ``o`` for good (at that step's matching and at every later step that
  writes the label); an object no label holds for good is discovered at the first step it is
  held. Discovery rank orders objects by that step, then by the order of their entries in
  that step's map (never by id string, which would put ``Chair_10`` before ``Chair_2``).
* Miller's law and TBS track *labels* across steps, as the paper does (Appendix B).
"""

from __future__ import annotations

import math
from dataclasses import dataclass
from itertools import groupby, pairwise

import numpy as np

from pytest_emrd.metrics._match import (
    EMPTY_MATCHING,
    Matcher,
    Matching,
    StepMatch,
    exp_ratio,
    layout_scale,
)
from pytest_emrd.trajectory import MapEntry, Trajectory


@dataclass(frozen=True)
class Spell:
    """One out-of-view interval of a mapped object (see :mod:`._tracking`)."""

    object_id: str
    category: str
    """Memory category of the object (``landmark``, ``salient``, ``clutter``)."""
    start: int
    """First out-of-view step ``s``."""
    duration: int
    """Steps out of view the object was retained: the event time, or the censoring time."""
    forgotten: bool
    """True for a forgetting event, False when right-censored."""
    discovery_rank: int
    """1-based rank of the object's discovery in its episode."""


@dataclass(frozen=True)
class RoomVisits:
    """First visit and first re-entry of one room (step indices, inclusive)."""

    room: str
    first_end: int
    return_end: int | None
    return_start: int | None = None
    """First step of the re-entry (None without one)."""


@dataclass(frozen=True, kw_only=True)
class Track:
    """Everything the temporal metrics read from one episode."""

    held: tuple[dict[str, str], ...]
    """For every step, object id -> label of the entry of ``M_t`` matched to it."""
    final: Matching
    """``match_map(M_T)`` of the terminal map on its own (empty when there is no step)."""
    spells: tuple[Spell, ...]
    """Every spell of every object, in start order."""
    discovery: dict[str, int]
    """Object id -> discovery rank (1-based)."""
    tbs: tuple[float, ...]
    """``TBS(t)`` for ``t = 1..T`` (empty when ``|G_base| = 0``)."""
    miller_loads: tuple[int, ...]
    """``m = |M_{t-1}|`` (distinct labels) for every step ``t >= 2`` with ``m >= 1``."""
    miller_forgets: tuple[bool, ...]
    """Whether ``M_{t-1} \\ M_t`` is non-empty, aligned with ``miller_loads``."""
    visits: tuple[RoomVisits, ...]
    """Rooms in order of first visit."""
    matcher: Matcher
    """The episode's matcher (its ground truth and type resolution)."""


def first_spells(spells: tuple[Spell, ...]) -> tuple[Spell, ...]:
    """The first spell of each object (its time-to-forget), in discovery order.

    One spell per object: later spells are conditional on re-discovery and would weight
    frequently re-seen objects (doorways) more than the rest.
    """
    first = {s.object_id: s for s in reversed(spells)}  # reversed: the earliest is kept
    return tuple(sorted(first.values(), key=lambda s: s.discovery_rank))


def track_episode(traj: Trajectory) -> Track:
    """Walk the steps once (see the module docstring for every definition).

    :param traj: The episode.
    :returns: Its :class:`Track`: what the temporal metrics read.
    """
    gt = traj.ground_truth
    g_base = len(gt.discoverable_ids)
    matcher = Matcher(gt.objects, g_base)
    scale = layout_scale(np.array([(o.x, o.z) for o in gt.objects], dtype=float).reshape(-1, 2))
    matches: list[StepMatch] = []
    tbs: list[float] = []
    first_pos: dict[str, tuple[float, float]] = {}
    found: StepMatch | None = None
    for step in traj.steps:
        found = matcher.step(step.cognitive_map, found)
        matches.append(found)
        for lb, e in found.entries.items():
            first_pos.setdefault(lb, (e.x, e.z))
        if g_base:
            tbs.append(_tbs_value(found, first_pos, scale, g_base))
    held = [matcher.held(m) for m in matches]
    written = [m.entries for m in matches]  # label -> its first entry, in the model's order
    # Miller's law: m = |M_{t-1}| labels for every non-empty M_{t-1}, and whether M_{t-1} \ M_t
    loads = tuple(len(before) for before, _ in pairwise(written) if before)
    forgets = tuple(not before.keys() <= now.keys() for before, now in pairwise(written) if before)
    when = discovered(held, written)
    discovery = {oid: rank for rank, oid in enumerate(sorted(when, key=when.__getitem__), 1)}
    return Track(
        held=tuple(held),
        final=matcher.match(traj.steps[-1].cognitive_map) if traj.steps else EMPTY_MATCHING,
        spells=_spells(traj, held, matches, matcher, discovery),
        discovery=discovery,
        tbs=tuple(tbs),
        miller_loads=loads,
        miller_forgets=forgets,
        visits=_visits([s.room for s in traj.steps]),
        matcher=matcher,
    )


def discovered(
    held: list[dict[str, str]], written: list[dict[str, MapEntry]]
) -> dict[str, tuple[int, int, bool]]:
    """Object id -> ``(discovery step (0-based), position of its entry in that step's map,
    discovered by a withdrawn pairing only)``: the key discovery ranks are ordered by."""
    kept = _kept_pairings(held, written)

    def at(t: int, label: str) -> int:
        return list(written[t]).index(label)

    first: dict[str, tuple[int, int, bool]] = {}
    fallback: dict[str, tuple[int, int, bool]] = {}
    seen: set[tuple[str, str]] = set()
    for t, h in enumerate(held):
        for oid, label in h.items():
            if oid not in fallback:  # held by a withdrawn pairing only: after a kept one
                fallback[oid] = (t, at(t, label), True)
            if (oid, label) in kept[t] and (oid, label) not in seen:
                seen.add((oid, label))  # kept from here on: its first step is the earliest
                since = _unchanged_since(written, label, t)
                when = (since, at(since, label), False)
                first[oid] = min(first.get(oid, when), when)
    return {oid: first.get(oid, at) for oid, at in fallback.items()}


def _unchanged_since(written: list[dict[str, MapEntry]], label: str, t: int) -> int:
    """The first step of the run of steps up to ``t`` writing ``label``'s entry of step ``t``
    unchanged (type and position)."""
    entry = written[t][label]
    since = t
    while since > 0:
        before = written[since - 1].get(label)
        if before is None or (before.object_type, before.x, before.z) != (
            entry.object_type,
            entry.x,
            entry.z,
        ):
            break
        since -= 1
    return since


_WITHDRAWN = ""
"""A label that a later step shows without the object it holds now (or with another one)."""


def _kept_pairings(
    held: list[dict[str, str]], written: list[dict[str, MapEntry]]
) -> list[set[tuple[str, str]]]:
    """For every step, the ``(object, label)`` pairs the label keeps at every later step that
    writes it (walked backwards; :data:`_WITHDRAWN` marks a label whose later objects differ)."""
    later: dict[str, str] = {}
    kept: list[set[tuple[str, str]]] = [set() for _ in held]
    for t in reversed(range(len(held))):
        holds = {label: oid for oid, label in held[t].items()}
        for oid, label in held[t].items():
            if later.get(label, oid) == oid:
                kept[t].add((oid, label))
        for label in written[t]:
            now = holds.get(label, _WITHDRAWN)
            later[label] = now if later.get(label, now) == now else _WITHDRAWN
    return kept


def _spells(
    traj: Trajectory,
    held: list[dict[str, str]],
    matches: list[StepMatch],
    matcher: Matcher,
    discovery: dict[str, int],
) -> tuple[Spell, ...]:
    """Every spell, following each object's holder label (module docstring)."""
    objects = {o.object_id: o for o in traj.ground_truth.objects}
    open_at: dict[str, tuple[int, str]] = {}  # object -> (start, holder label)
    done: list[tuple[int, str, int, bool]] = []  # (start, object, duration, forgotten)
    prev_visible: frozenset[str] = frozenset()
    for i, step in enumerate(traj.steps):
        t = step.index
        visible = frozenset(step.visible_ids)
        for oid in (prev_visible - visible) & held[i - 1].keys():  # none at i = 0
            open_at[oid] = (t, held[i - 1][oid])
        kinds = matches[i].kind_of
        for oid, (start, label) in list(open_at.items()):
            if oid in visible:
                done.append((start, oid, t - start, False))
            elif kinds.get(label, -1) != matcher.types.index[objects[oid].object_type]:
                done.append((start, oid, t - start + 1, True))  # dropped, or relabelled away
            else:
                continue
            del open_at[oid]
        prev_visible = visible
    if traj.steps:
        last = traj.steps[-1].index
        done.extend((s, oid, last - s + 1, False) for oid, (s, _) in open_at.items())
    done.sort()  # by start, then object: an object has one spell open at a time
    return tuple(
        Spell(oid, objects[oid].category, start, duration, forgotten, discovery[oid])
        for start, oid, duration, forgotten in done
    )


def _tbs_value(
    found: StepMatch, first_pos: dict[str, tuple[float, float]], scale: float, g_base: int
) -> float:
    """``TBS(t)`` of one step: 0.0 when nothing is matched (coverage 0)."""
    if not found.identity:
        return 0.0
    entries = found.entries
    drift = math.fsum(
        math.hypot(entries[lb].x - first_pos[lb][0], entries[lb].z - first_pos[lb][1])
        for lb in sorted(found.identity)
    )
    n = len(found.identity)
    return exp_ratio(drift / n, scale) * min(n, g_base) / g_base


def _visits(rooms: list[str]) -> tuple[RoomVisits, ...]:
    visits: dict[str, RoomVisits] = {}
    end = -1
    for room, run in groupby(rooms):
        start, end = end + 1, end + len(list(run))
        known = visits.get(room)
        if known is None:
            visits[room] = RoomVisits(room, end, None)
        elif known.return_end is None:
            visits[room] = RoomVisits(room, known.first_end, end, start)
    return tuple(visits.values())
