"""What every scripted agent does with a view: place objects, guess the room, remember.

Every visible object is placed in the spawn frame from the pose and its bearing/distance
(perfect odometry). The current room is inferred by matching the object types in view
against the prompt's inventory (types found in fewer rooms and nearer objects weigh more);
objects seen through a doorway lie in the next room and neither vote nor get a room. The
reported map then passes through the planted memory (:mod:`._memory`). Navigation reads
its own perfect record in the ``plan`` (:func:`fresh_plan`), never the reported map, so
every memory variant of an agent walks the same path.
"""

from __future__ import annotations

import math
from collections.abc import Mapping
from typing import Any, Final

from pytest_emrd.reference._memory import Draw, Entry, apply_memory, merge_view
from pytest_emrd.reference._read import Briefing, Percept, placed
from pytest_emrd.world import VisibleObject

DOORWAY: Final = "Doorway"
#: A sweep: the view on arrival plus this many ``Turn(Right)``, 360 degrees in all.
SWEEP_TURNS: Final = 3
#: A pose this far (m) from the previous one means the last Goto moved the agent.
MOVED_M: Final = 0.3
#: Bearings are clipped to the field of view: a sighting at the edge misplaces the centre.
EDGE_DEG: Final = 44.9
#: Lateral half-width (m) of the cone behind a visible doorway treated as the next room.
GAP_HALF_WIDTH_M: Final = 1.0
#: The navigation state (:func:`fresh_plan`), carried in the ``plan`` key of every reply.
Plan = dict[str, Any]
#: Plan keys that outlive a room visit; entering a room resets the others to :func:`fresh_plan`.
EPISODE_KEYS: Final = (
    "acted",
    "reach",
    "visited",
    "used",
    "doors",
    "door_rooms",
    "order",
    "rough",
    "sizes",
    "at",
)


def fresh_plan() -> Plan:
    """Navigation state at the first step, carried in the ``plan`` key of every reply."""
    return {
        # sweep (turning in place), decide, face (turning towards the target), cross / walk
        # (just sent Goto through a doorway / to an object)
        "phase": "sweep",
        "turns": 0,  # Turn(Right) of this sweep
        "votes": {},  # this visit: room -> vote
        "here": {},  # this visit: doorway seen -> distance
        "found": 0,  # this visit: objects discovered
        "spots": {},  # this visit: object id -> [x, z, type]
        "near": [],  # ids of the current sweep
        "sweeps": [],  # this visit: where each sweep began
        "moves": 0,  # this visit: repositions made
        "clears": 0,  # this visit: clearing moves made
        "acted": 0,  # actions of the episode
        "reach": 0.0,  # distance of the farthest doorway seen
        "tried": [],  # this visit: spots tried
        "blocked": [],  # this visit: doorways given up
        "visited": [],  # rooms
        "used": [],  # doorways crossed, least recent first
        "doors": {},  # doorway id -> [x, z]
        "door_rooms": {},  # doorway id -> rooms it was seen inside
        "order": [],  # object ids in order of discovery
        "rough": [],  # object ids placed at the edge of view
        "sizes": {},  # room -> objects discovered in it
        "target": "",  # what to face and Goto
        "goal": "",  # door or spot
        "tries": 0,  # turns made to face the target
        "at": [0.0, 0.0],  # pose at the last step
    }


def room_guess(plan: Mapping[str, Any]) -> str:
    """The room the votes point to ("" before any vote; ties: prompt order)."""
    votes: dict[str, float] = plan["votes"]
    return max(votes, key=votes.__getitem__, default="")  # max keeps the first of equals


def _inside(visible: tuple[VisibleObject, ...]) -> tuple[VisibleObject, ...]:
    doors = [s for s in visible if s.object_type == DOORWAY]

    def behind(seen: VisibleObject) -> bool:
        return any(
            seen.distance > d.distance
            and abs(seen.bearing - d.bearing)
            <= math.degrees(math.atan2(GAP_HALF_WIDTH_M, d.distance))
            for d in doors  # seen itself is no farther than seen
        )

    return tuple(s for s in visible if not behind(s))


def _vote(plan: Plan, briefing: Briefing, visible: tuple[VisibleObject, ...]) -> None:
    votes = plan["votes"] or dict.fromkeys(briefing.inventory, 0.0)
    for seen in visible:
        rooms = [room for room, counts in briefing.inventory.items() if seen.object_type in counts]
        for room in rooms:
            votes[room] = round(votes[room] + 1.0 / len(rooms) / (1.0 + seen.distance), 4)
    plan["votes"] = votes if any(votes.values()) else {}


def _enter_room(plan: Plan) -> None:
    plan["used"] = [d for d in plan["used"] if d != plan["target"]] + [plan["target"]]
    plan.update((key, value) for key, value in fresh_plan().items() if key not in EPISODE_KEYS)


def _after_goto(plan: Plan, moved: bool) -> None:
    """Bookkeeping at the step after a ``Goto`` (``phase`` ``cross`` or ``walk``)."""
    if plan["phase"] == "cross":
        if moved:
            _enter_room(plan)
        else:
            plan.update(phase="face", tries=plan["tries"] + 1)
    elif plan["phase"] == "walk":
        # Arrived: sweep from here. Not moved (no free spot there): decide again at once.
        plan.update(phase="sweep" if moved else "decide", turns=0, target="", goal="", tries=0)
        if moved:  # a doorway out of view from the last spot may be in view from this one
            plan["blocked"] = []


def perceive(
    plan: Plan,
    memory: dict[str, Entry],
    briefing: Briefing,
    percept: Percept,
    *,
    planted: Mapping[str, Any],
    draw: Draw,
) -> tuple[dict[str, Entry], list[str]]:
    """Update the plan with this view; return the remembered map and the new labels."""
    pose = percept.pose
    _after_goto(plan, math.dist(plan["at"], (pose.x, pose.z)) > MOVED_M)
    plan["at"] = [round(pose.x, 2), round(pose.z, 2)]
    if plan["phase"] == "sweep" and plan["turns"] == 0:  # a sweep begins with this view
        plan["sweeps"].append(plan["at"])
        plan["near"] = []
    inside_view = _inside(percept.visible)
    inside = {s.object_id for s in inside_view}
    _vote(plan, briefing, inside_view)
    room = room_guess(plan)
    view: dict[str, Entry] = {}  # label -> entry, farthest first
    for seen in sorted(percept.visible, key=lambda s: (-s.distance, s.object_id)):
        oid = seen.object_id
        x, z = (round(v, 2) for v in placed(percept, seen))
        if seen.object_type == DOORWAY:
            plan["doors"][oid] = [x, z]
            plan["reach"] = max(plan["reach"], round(seen.distance, 2))
            rooms = plan["door_rooms"].setdefault(oid, [])
            if oid in inside:  # Goto of a doorway seen through another stops short
                plan["here"].setdefault(oid, round(seen.distance, 2))
                if room and room not in rooms:
                    rooms.append(room)
        elif oid in inside:
            plan["spots"][oid] = [x, z, seen.object_type]
            if oid not in plan["near"]:
                plan["near"].append(oid)
        entry: Entry = {"type": seen.object_type, "x": x, "z": z}
        old = memory.get(oid, {})
        if abs(seen.bearing) < EDGE_DEG:
            if oid in plan["rough"]:
                plan["rough"].remove(oid)
        elif oid not in plan["rough"]:  # a first edge sighting: keep a clear one if any
            if "x" in old:
                entry.update(x=old["x"], z=old["z"])
            else:
                plan["rough"].append(oid)
        old_room = old.get("room")
        if old_room or (room and oid in inside):
            entry["room"] = old_room or room
        view[oid] = entry
    new = [label for label in reversed(view) if label not in plan["order"]]
    plan["order"] += new
    plan["found"] += len(new)
    kept = apply_memory(
        merge_view(memory, view),
        in_view=frozenset(view),
        planted=planted,
        discovery=plan["order"],
        draw=draw,
        expected=sum(n for counts in briefing.inventory.values() for n in counts.values()),
    )
    return kept, new
