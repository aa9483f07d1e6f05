"""Seeded synthetic trajectories with planted, known cognition.

Used by the metrics benchmark and by property tests, and handy for anyone who wants to see
what the metrics report on data whose answer is known. Nothing here touches the world or
agent stages: the office, the walk and the "model" are drawn directly.

What is planted:

* **Office.** A 2x2 office of four 6 m x 5 m rooms (Office top-left, Conference Room
  top-right, Kitchen bottom-left, Entrance bottom-right) joined by four doorways, with 39
  objects: Office 12 (desks, chairs, laptops, shelving, plant), Conference Room 10 (one table,
  eight chairs, television), Kitchen 8, Entrance 5 (incl. the exit door), 4 doorways. Furniture
  positions are drawn per ``(spawn, episode)``; ids follow ``Type_N``. The spawn frame is the
  world frame translated to the spawn room's centre.
* **Walk.** The agent stays 3-7 steps in a room, then moves to a random adjacent room (so
  rooms are re-entered). Each step it sees each object of its room with probability
  ``visibility`` (baseline 0.5; low light 0.3; texture 0.45) and each of the room's doorways
  with probability 0.7. About 5 % of objects are not discoverable under the baseline.
* **Model.** A seen object enters the map with probability 0.85 under a label of the model's
  own (``Chair_1`` numbered in the model's order, types written with synonyms such as ``TV``,
  ``table`` or ``door frame``) at its true position plus N(0, 0.3 m) noise; entries drift by
  N(0, 0.05 m) now and then; one hallucinated ``Sofa`` appears with probability 0.02 per step;
  3 % of replies fail to parse (the map carries over). **Forgetting:** at every step out of
  view, a held object is dropped with probability ``1 / mean_memory`` -- geometric, the
  discrete exponential, so spells' time-to-forget has mean ``mean_memory`` and the censored
  MLE (Eq. SMLE) estimates it.
* **Decision.** ``Term`` after 25-50 steps in 60 % of episodes (budget otherwise), naming the
  Conference Room (60 %), Entrance (30 %), Kitchen or Office (5 % each).
"""

from __future__ import annotations

import json
from collections import Counter
from collections.abc import Sequence
from importlib import resources
from typing import Final

import numpy as np

from pytest_emrd.rooms import ROOM_SLUGS, SLUG_ROOMS
from pytest_emrd.trajectory import (
    CONDITIONS,
    MAX_STEPS,
    EpisodeSpec,
    GroundTruth,
    GroundTruthObject,
    MapEntry,
    Pose,
    RoomOutline,
    Step,
    Trajectory,
)

__all__ = ["synthetic_grid", "synthetic_trajectory"]

#: The planted office and model as data (``synthetic.json`` beside this module): rooms as
#: ``(x0, z0, x1, z1)``, doorways, furniture ``(type, count, category)`` per room, spellings per
#: type, visibility per condition, the chosen rooms' probabilities and their rationales.
_DATA: Final = json.loads(
    resources.files(__package__).joinpath("synthetic.json").read_text("utf-8")
)
_ROOMS: Final[dict[str, list[float]]] = _DATA["rooms"]
_DOORWAYS: Final[list[tuple[str, str, float, float]]] = _DATA["doorways"]


def _corners(room: str) -> np.ndarray:
    """The lower-left ``(x0, z0)`` and upper-right ``(x1, z1)`` corners of ``room``, as rows."""
    return np.reshape(_ROOMS[room], (2, 2))


def _layout(
    rng: np.random.Generator, spawn_room: str
) -> tuple[GroundTruth, dict[str, list[GroundTruthObject]], np.ndarray]:
    """The office in the spawn frame, each room's doorways, and the spawn frame's origin."""
    low, high = _corners(spawn_room)
    origin = (low + high) / 2
    counters: Counter[str] = Counter()
    objects: list[GroundTruthObject] = []

    def add(kind: str, room: str, category: str, x: float, z: float) -> GroundTruthObject:
        counters[kind] += 1
        oid = f"{kind}_{counters[kind]}"
        obj = GroundTruthObject(oid, kind, room, category, x - origin[0], z - origin[1])
        objects.append(obj)
        return obj

    doorways: dict[str, list[GroundTruthObject]] = {r: [] for r in _ROOMS}
    for room_a, room_b, x, z in _DOORWAYS:
        door = add("Doorway", room_a, "landmark", x, z)
        doorways[room_a].append(door)
        doorways[room_b].append(door)
    for room, items in _DATA["furniture"].items():
        low, high = _corners(room)
        for kind, count, category in items:
            for _ in range(count):
                add(kind, room, category, *rng.uniform(low + 0.5, high - 0.5))
    hidden = rng.random(len(objects)) < 0.05
    outlines = tuple(
        RoomOutline(
            name,
            tuple(
                (float(x - origin[0]), float(z - origin[1]))
                for x, z in ((x0, z0), (x1, z0), (x1, z1), (x0, z1))
            ),
        )
        for name, (x0, z0, x1, z1) in _ROOMS.items()
    )
    discoverable = tuple(sorted(o.object_id for o, h in zip(objects, hidden, strict=True) if not h))
    truth = GroundTruth(tuple(objects), outlines, discoverable, spawn_room)
    return truth, doorways, origin


def _neighbours(room: str) -> list[str]:
    return sorted({b if a == room else a for a, b, _, _ in _DOORWAYS if room in (a, b)})


def synthetic_trajectory(
    spec: EpisodeSpec, *, mean_memory: float = 10.0, seed: int = 0
) -> Trajectory:
    """One synthetic episode for ``spec`` (see the module docstring for what is planted).

    Deterministic in ``(spec, mean_memory, seed)``. ``mean_memory`` is the planted mean
    time-to-forget in steps (> 1); ``spec.max_steps`` bounds the episode.
    """
    rng = np.random.default_rng([seed, spec.seed, sum(map(ord, spec.model + spec.condition))])
    spawn_room = SLUG_ROOMS[spec.spawn]
    truth, doorways, origin = _layout(np.random.default_rng(spec.seed), spawn_room)
    hazard = 1.0 / max(mean_memory, 1.0)
    p_visible = _DATA["visibility"].get(spec.condition, 0.5)
    discoverable = set(truth.discoverable_ids)
    furniture = {  # what a room can show besides its doorways
        r: [o for o in truth.objects if o.room == r and o.object_type != "Doorway"] for r in _ROOMS
    }
    terminate = rng.random() < 0.6
    n_steps = int(rng.integers(25, spec.max_steps + 1)) if terminate else spec.max_steps
    held: dict[str, tuple[str, str, float, float]] = {}  # object id -> (label, type text, x, z)
    extras: dict[str, MapEntry] = {}
    type_counts: Counter[str] = Counter()
    room, stay = spawn_room, int(rng.integers(3, 8))
    steps: list[Step] = []
    cog_map: tuple[MapEntry, ...] = ()
    for t in range(1, n_steps + 1):
        if stay == 0:
            room, stay = str(rng.choice(_neighbours(room))), int(rng.integers(3, 8))
        stay -= 1
        seen = [
            o for o in furniture[room] if o.object_id in discoverable and rng.random() < p_visible
        ]
        seen += [o for o in doorways[room] if rng.random() < 0.7]
        visible = {o.object_id for o in seen}
        for oid in list(held):
            if oid not in visible and rng.random() < hazard:
                del held[oid]
        for o in seen:
            if o.object_id not in held and rng.random() < 0.85:
                type_counts[o.object_type] += 1
                spelling = str(rng.choice(_DATA["spellings"].get(o.object_type, [o.object_type])))
                x, z = rng.normal((o.x, o.z), 0.3)
                label = f"{o.object_type}_{type_counts[o.object_type]}"
                held[o.object_id] = (label, spelling, float(x), float(z))
        for oid, (label, spelling, x, z) in list(held.items()):
            if rng.random() < 0.2:
                dx, dz = rng.normal(0.0, 0.05, 2)
                held[oid] = (label, spelling, x + float(dx), z + float(dz))
        if rng.random() < 0.02:
            label = f"Sofa_{len(extras) + 1}"
            extras[label] = MapEntry(label, "Sofa", *map(float, rng.uniform(-6, 6, 2)), room)
        failed = rng.random() < 0.03 and t > 1
        if not failed:
            cog_map = tuple(
                MapEntry(label, spelling, round(x, 3), round(z, 3), room)
                for label, spelling, x, z in held.values()
            ) + tuple(extras.values())
        low, high = _corners(room)
        px, pz = rng.uniform(low + 1, high - 1) - origin
        is_term = terminate and t == n_steps
        steps.append(
            Step(
                index=t,
                pose=Pose(float(px), float(pz), float(90 * rng.integers(0, 4))),
                room=room,
                visible_ids=tuple(sorted(visible)),
                cognitive_map=cog_map,
                action="" if failed else ("Term" if is_term else "Turn(Right)"),
                success=not failed,
                feedback="could not read the reply" if failed else "ok",
                parse_error="no JSON object in the reply" if failed else None,
            )
        )
    rooms, p = zip(*_DATA["choices"].items(), strict=True)
    chosen = rooms[rng.choice(len(rooms), p=p)] if terminate else None
    return Trajectory(
        spec=spec,
        protocol="synthetic-1",
        ground_truth=truth,
        steps=tuple(steps),
        status="terminated" if terminate else "budget",
        final_room=room,
        chosen_room=chosen,
        chosen_room_raw=chosen,
        rationale=_DATA["rationales"][chosen] if chosen else None,
    )


def synthetic_grid(
    *,
    model: str = "synthetic",
    conditions: Sequence[str] = CONDITIONS,
    episodes: int = 20,
    max_steps: int = MAX_STEPS,
    mean_memory: float = 10.0,
    seed: int = 0,
) -> list[Trajectory]:
    """A model x conditions x 4 spawns x ``episodes`` grid (default 240 episodes of 50 steps)."""
    return [
        synthetic_trajectory(
            EpisodeSpec(model, condition, slug, episode, max_steps=max_steps),
            mean_memory=mean_memory,
            seed=seed,
        )
        for condition in conditions
        for slug in ROOM_SLUGS.values()
        for episode in range(episodes)
    ]
