"""The scripted reference policies: ``scout`` (room clearing) and ``prior`` (textual prior).

Both run the same perception: every visible object is placed in the spawn frame from the
pose and its bearing/distance (perfect odometry, so a perfect-memory scout maps exactly),
the current room is inferred by matching the object types in view against the prompt's
inventory (types found in fewer rooms weigh more, nearer objects weigh more), and the
reported map passes through the planted memory (:mod:`._memory`). Navigation uses its
own perfect record of doorways, kept in the ``plan`` key of the reply, so every scout
variant walks the same path and only the reported map differs.

``scout`` protocol, per room: the entry view plus three ``Turn(Right)`` sweep 360 degrees;
then it turns towards a doorway seen in this room (unused ones first, nearest first; else
the one used longest ago) and walks through it with ``Goto``. Term rule: once it has
identified every room of the prompt, or no doorway is left to try, or at the last step,
it names the room where it discovered the most objects (ties: prompt order; rooms it
could not identify, as under ``no_inventory``, fall back to the first room listed).

``prior``: sweeps the spawn room, then terminates naming the room it has not entered
whose inventory lists the most seats (chairs, sofas, stools) — the furniture prior the
paper found behind the Conference Room choice.
"""

from __future__ import annotations

import math
from collections.abc import Callable, Mapping
from typing import Any, Final

from pytest_emrd.agent.reference._memory import apply_memory, merge_view
from pytest_emrd.agent.reference._read import Briefing, Percept, Seen

DOORWAY: Final = "Doorway"
SWEEP_TURNS: Final = 3
MAX_FACE_TRIES: Final = 2
MOVED_M: Final = 0.3
#: Bearings are clipped to the field of view: a sighting at the edge misplaces the centre.
EDGE_DEG: Final = 44.9
#: Lateral half-width (m) of the cone behind a visible doorway treated as the next room.
GAP_HALF_WIDTH_M: Final = 1.0
_SEATS: Final = ("Chair", "Sofa", "Stool")


def fresh_plan() -> dict[str, Any]:
    return {
        "phase": "sweep",
        "turns": 0,
        "votes": {},
        "here": {},
        "found": 0,
        "visited": [],
        "used": [],
        "blocked": [],
        "doors": {},
        "order": [],
        "rough": [],
        "sizes": {},
        "target": "",
        "tries": 0,
        "at": [0.0, 0.0],
    }


def _place(percept: Percept, seen: Seen) -> tuple[float, float]:
    angle = math.radians(percept.pose.heading + seen.bearing)
    x = percept.pose.x + seen.distance * math.sin(angle)
    z = percept.pose.z + seen.distance * math.cos(angle)
    return round(x, 2), round(z, 2)


def _room_guess(plan: Mapping[str, Any]) -> str:
    votes: dict[str, float] = plan["votes"]
    return max(votes, key=lambda r: (votes[r], -list(votes).index(r)), default="")


def _inside(visible: tuple[Seen, ...]) -> tuple[Seen, ...]:
    """Objects in view that are not seen through a doorway (those lie in the next room)."""
    doors = [s for s in visible if s.object_type == DOORWAY]

    def behind(seen: Seen) -> bool:
        return any(
            seen.distance > d.distance
            and abs(seen.bearing - d.bearing)
            <= math.degrees(math.atan2(GAP_HALF_WIDTH_M, d.distance))
            for d in doors
            if d is not seen
        )

    return tuple(s for s in visible if not behind(s))


def _vote(plan: dict[str, Any], briefing: Briefing, visible: tuple[Seen, ...]) -> None:
    holders: dict[str, list[str]] = {}
    for room, counts in briefing.inventory.items():
        for t in counts:
            holders.setdefault(t, []).append(room)
    votes = plan["votes"] or {room: 0.0 for room in briefing.inventory}
    for seen in visible:
        rooms = holders.get(seen.object_type, [])
        for room in rooms:
            votes[room] = round(votes[room] + 1.0 / len(rooms) / (1.0 + seen.distance), 4)
    plan["votes"] = votes if any(votes.values()) else {}


def _enter_room(plan: dict[str, Any]) -> None:
    """Reset per-room bookkeeping after walking through a doorway."""
    plan.update(phase="sweep", turns=0, votes={}, here={}, found=0, tries=0)
    plan["used"] = [d for d in plan["used"] if d != plan["target"]] + [plan["target"]]
    plan["blocked"], plan["target"] = [], ""


def perceive(
    plan: dict[str, Any],
    memory: dict[str, dict[str, Any]],
    briefing: Briefing,
    percept: Percept,
    *,
    planted: Mapping[str, Any],
    draw: Callable[[str], float],
) -> tuple[dict[str, dict[str, Any]], list[str]]:
    """Update the plan with this view; return the remembered map and the new labels."""
    pose = percept.pose
    if plan["phase"] == "cross":
        moved = math.dist(plan["at"], (pose.x, pose.z)) > MOVED_M
        if moved:
            _enter_room(plan)
        else:
            plan.update(phase="face", tries=plan["tries"] + 1)
    plan["at"] = [round(pose.x, 2), round(pose.z, 2)]
    inside = {s.object_id for s in _inside(percept.visible)}
    _vote(plan, briefing, tuple(s for s in percept.visible if s.object_id in inside))
    room = _room_guess(plan)
    view = []
    for seen in sorted(percept.visible, key=lambda s: (-s.distance, s.object_id)):
        x, z = _place(percept, seen)
        if seen.object_type == DOORWAY:
            plan["doors"][seen.object_id] = [x, z]
            plan["here"].setdefault(seen.object_id, round(seen.distance, 2))
        entry: dict[str, Any] = {"type": seen.object_type, "x": x, "z": z}
        old = memory.get(seen.object_id, {})
        if abs(seen.bearing) >= EDGE_DEG:
            if seen.object_id not in plan["rough"] and "x" in old:
                entry.update(x=old["x"], z=old["z"])
            elif seen.object_id not in plan["rough"]:
                plan["rough"].append(seen.object_id)
        elif seen.object_id in plan["rough"]:
            plan["rough"].remove(seen.object_id)
        old_room = old.get("room")
        if old_room or (room and seen.object_id in inside):
            entry["room"] = old_room or room
        view.append((seen.object_id, entry))
    new = [label for label, _ in reversed(view) if label not in plan["order"]]
    plan["order"] += new
    plan["found"] += len(new)
    merged = merge_view(memory, view)
    kept = apply_memory(
        merged,
        in_view=frozenset(label for label, _ in view),
        planted=planted,
        discovery=plan["order"],
        draw=draw,
    )
    return kept, new


def _close_room(plan: dict[str, Any]) -> None:
    room = _room_guess(plan)
    if room:
        if room not in plan["visited"]:
            plan["visited"].append(room)
        plan["sizes"][room] = plan["sizes"].get(room, 0) + plan["found"]
    plan["found"] = 0


def _next_door(plan: Mapping[str, Any]) -> str:
    here: dict[str, float] = plan["here"]
    used: list[str] = plan["used"]
    options = [d for d in here if d not in plan["blocked"]]
    unused = sorted((d for d in options if d not in used), key=lambda d: (here[d], d))
    if unused:
        return unused[0]
    return min((d for d in options), key=used.index, default="")


def _turn_towards(plan: Mapping[str, Any], percept: Percept, door: str) -> str:
    x, z = plan["doors"][door]
    angle = math.degrees(math.atan2(x - percept.pose.x, z - percept.pose.z))
    rel = (angle - percept.pose.heading + 180.0) % 360.0 - 180.0
    if abs(rel) > 135.0:
        return "Turn(Around)"
    return "Turn(Right)" if rel > 0 else "Turn(Left)"


def term_choice(plan: Mapping[str, Any], briefing: Briefing) -> tuple[str, str]:
    """(room, reasoning) under the scout's Term rule."""
    sizes: dict[str, int] = plan["sizes"]
    if not sizes:
        return briefing.rooms[0], "No room could be identified; naming the first room listed."
    order = list(briefing.rooms)
    room = max(sizes, key=lambda r: (sizes[r], -order.index(r) if r in order else 0))
    return room, f"Term rule: the room where I mapped the most objects ({room}: {sizes[room]})."


def scout_action(plan: dict[str, Any], briefing: Briefing, percept: Percept) -> tuple[str, str]:
    """(action, reasoning) of the room-clearing scout."""
    visible = {s.object_id for s in percept.visible}
    if percept.step >= percept.max_steps:
        _close_room(plan)
        room, why = term_choice(plan, briefing)
        return f"Term({room})", f"Last action of the budget. {why}"
    if plan["phase"] == "sweep":
        if plan["turns"] < SWEEP_TURNS:
            plan["turns"] += 1
            return "Turn(Right)", f"Sweeping the room ({plan['turns']}/{SWEEP_TURNS})."
        _close_room(plan)
        plan.update(phase="face", tries=0, target=_next_door(plan))
        explored = not set(plan["doors"]) - set(plan["used"])
        if len(plan["visited"]) >= len(briefing.rooms) or explored or not plan["target"]:
            room, why = term_choice(plan, briefing)
            return f"Term({room})", why
    while plan["target"]:
        door = plan["target"]
        if plan["tries"] <= MAX_FACE_TRIES and door in visible:
            plan["phase"] = "cross"
            return f"Goto({door})", f"Advancing through {door}."
        if plan["tries"] < MAX_FACE_TRIES:
            plan["tries"] += 1
            return _turn_towards(plan, percept, door), f"Turning towards {door}."
        plan["blocked"].append(door)
        plan.update(tries=0, target=_next_door(plan))
    room, why = term_choice(plan, briefing)
    return f"Term({room})", f"No doorway left to try. {why}"


def _seats(counts: Mapping[str, int]) -> int:
    return sum(n for t, n in counts.items() if any(s in t for s in _SEATS))


def prior_action(plan: dict[str, Any], briefing: Briefing, percept: Percept) -> tuple[str, str]:
    """(action, reasoning) of the prior agent: sweep the spawn room, then name another."""
    if plan["turns"] < SWEEP_TURNS and percept.step < percept.max_steps:
        plan["turns"] += 1
        return "Turn(Right)", f"Looking around ({plan['turns']}/{SWEEP_TURNS})."
    _close_room(plan)
    here = set(plan["visited"])
    others = [r for r in briefing.rooms if r not in here] or list(briefing.rooms)
    inventory = briefing.inventory
    room = max(others, key=lambda r: (_seats(inventory.get(r, {})), -others.index(r)))
    return (
        f"Term({room})",
        f"{room} has the most seating for a gathering ({_seats(inventory.get(room, {}))} seats).",
    )
