"""The room-clearing ``scout`` policy.

Per room visit, the entry view plus three ``Turn(Right)`` sweep 360 degrees; then the scout
decides, in this order:

1. every room of the prompt identified: in the last room, clear it as in rule 2; else ``Term``;
2. **clear the room** while it is not complete, the visit has a clearing move left and the
   budget affords one: ``Goto`` the object of the last sweep farthest from where this visit
   swept, among those from which a known doorway can be seen again, and sweep again;
3. an unused doorway seen during this visit (nearest first): face it, ``Goto`` through;
4. **reposition** while rooms remain unvisited, the visit has a move left and the room is not
   complete (a doorway and every object of its inventory line seen during this visit):
   ``Goto`` an object of the last sweep, at least :data:`MIN_MOVE_M` away and not tried: the
   one nearest to an unused doorway known to open from this room, else the one farthest from
   where this visit swept; then sweep again;
5. every doorway it knows of already used: ``Term``;
6. the doorway of this visit used longest ago: back through it;
7. otherwise ``Term``.

A target still out of view after :data:`MAX_FACE_TRIES` turns is given up (a doorway is
first approached from the nearest object of the last sweep). Objects are legible within
about 3 m and furniture occludes, so rules 2 and 4 walk the scout into a room's far parts, and
darkness costs coverage *and* time, as the paper reports for real models. Term rule: the
room where it discovered the most objects (ties: prompt order; none identified: the first).

**Homing** (the ``mimic`` ``b`` knob): at rule 1 a homing scout walks back into the room the
Term rule names (``home``, fixed when homing begins) through known doorways seen inside it,
or into a room with such a doorway, sweeping each room it enters: the room re-entries that
Spatial Identity Resolution needs.
"""

from __future__ import annotations

import math
from collections import Counter
from collections.abc import Mapping
from typing import Any, Final

from pytest_emrd.reference._perceive import SWEEP_TURNS, Plan, room_guess
from pytest_emrd.reference._read import Briefing, Percept

MAX_FACE_TRIES: Final = 2
#: Repositions per room visit (each costs about five actions of the 50).
MAX_MOVES: Final = 3
#: Repositions of a visit that has seen no doorway yet (lost in the dark).
LOST_MOVES: Final = 6
#: Clearing moves per room visit (rule 2), besides the repositions.
MAX_CLEARS: Final = 2
#: A reposition target lies at least this far (m) from where the scout stands.
MIN_MOVE_M: Final = 1.0
#: Actions a reposition may need (turns to face, Goto, three sweep turns).
RESERVE: Final = 6
#: Actions kept per room not yet visited (face a doorway, cross, sweep).
PER_ROOM: Final = 6


def _close_room(plan: Plan) -> None:
    room = room_guess(plan)
    if room:
        if room not in plan["visited"]:
            plan["visited"].append(room)
        plan["sizes"][room] = plan["sizes"].get(room, 0) + plan["found"]
    plan["found"] = 0


def _complete(plan: Mapping[str, Any], briefing: Briefing) -> bool:
    """A doorway and every object of the room's inventory line seen during this visit."""
    counts = briefing.inventory.get(room_guess(plan))
    if not counts or not plan["here"]:
        return False
    return Counter(spot[2] for spot in plan["spots"].values()) >= Counter(counts)


def _spot(
    plan: Mapping[str, Any], towards: list[list[float]], within: list[list[float]] | None = None
) -> str:
    """An object of the last sweep to reposition at ("" when none): the one nearest to a
    point of ``towards`` and nearer to it than the scout, else the one farthest from this
    visit's sweeps; ``within``: only objects no farther from one of these points than the
    farthest a doorway has been seen (``reach``)."""
    xz = {o: plan["spots"][o][:2] for o in plan["near"]}  # each object's [x, z]

    def gap(point: list[float]) -> float:
        return min(math.dist(point, p) for p in towards)

    candidates = [
        o
        for o in plan["near"]
        if math.dist(xz[o], plan["at"]) >= MIN_MOVE_M and o not in plan["tried"]
    ]
    if within is not None:
        candidates = [
            o for o in candidates if any(math.dist(xz[o], p) <= plan["reach"] for p in within)
        ]
    if towards:
        here = gap(plan["at"])
        closer = (o for o in candidates if gap(xz[o]) < here)
        return min(closer, key=lambda o: (gap(xz[o]), o), default="")
    return max(
        candidates, key=lambda o: (min(math.dist(xz[o], p) for p in plan["sweeps"]), o), default=""
    )


def _reposition(plan: Plan, towards: list[list[float]]) -> bool:
    """Rule 4's move towards ``towards``, if the visit has a reposition left."""
    limit = MAX_MOVES if plan["here"] else LOST_MOVES
    return _go_spot(plan, _spot(plan, towards) if plan["moves"] < limit else "", "moves")


def _go_spot(plan: Plan, spot: str, counter: str) -> bool:
    """Target ``spot`` (if any), counting the move in ``counter`` (``moves`` or ``clears``)."""
    if spot:
        plan["tried"].append(spot)
        plan.update(target=spot, goal="spot", phase="face", tries=0)
        plan[counter] += 1
    return bool(spot)


def _clear(plan: Plan, briefing: Briefing, percept: Percept) -> bool:
    """Rule 2, if the visit has a clearing move left and the budget affords it."""
    if plan["clears"] >= MAX_CLEARS or _complete(plan, briefing):
        return False
    doors = [xz for d, xz in plan["doors"].items() if d not in plan["blocked"]]
    # PER_ROOM actions kept per unvisited room, counting the scout's own actions (``acted``):
    # a wasted step (a planted invalid action) changes nothing.
    left = percept.max_steps - plan["acted"] - RESERVE
    affordable = left > PER_ROOM * (len(briefing.rooms) - len(plan["visited"]))
    return _go_spot(plan, _spot(plan, [], doors) if affordable else "", "clears")


def _choose(plan: Plan, briefing: Briefing, percept: Percept) -> None:
    """Set ``target`` and ``goal`` by rules 2-6; an empty target means ``Term``."""
    plan.update(phase="face", tries=0)
    if _clear(plan, briefing, percept):
        return
    here: dict[str, float] = plan["here"]
    used: list[str] = plan["used"]
    open_here = [d for d in here if d not in plan["blocked"]]
    door = min((d for d in open_here if d not in used), key=lambda d: (here[d], d), default="")
    if door:
        plan.update(target=door, goal="door")
        return
    room = room_guess(plan)
    doors = [
        plan["doors"][d]
        for d, rooms in plan["door_rooms"].items()
        if room in rooms and d not in used  # rooms never holds "" (no room identified)
    ]
    unvisited = len(plan["visited"]) < len(briefing.rooms)
    if unvisited and not _complete(plan, briefing) and _reposition(plan, doors):
        return
    explored = not set(plan["doors"]) - set(used)
    door = "" if explored else min((d for d in open_here if d in used), key=used.index, default="")
    plan.update(target=door, goal="door" if door else "")


def _turn_towards(percept: Percept, x: float, z: float) -> str:
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
    order = briefing.rooms
    room = max(sizes, key=lambda r: (sizes[r], -order.index(r) if r in order else 0))
    return room, f"Term rule: the room where I mapped the most objects ({room}: {sizes[room]})."


def _home_term(plan: Mapping[str, Any], briefing: Briefing) -> tuple[str, str]:
    """The Term rule, or the room homing set out for (named whatever happens on the way)."""
    home = plan.get("home", "")
    if home:
        return home, f"Back in the gathering room I chose: {home}."
    return term_choice(plan, briefing)


def _door_home(plan: Mapping[str, Any], home: str) -> str:
    """A known doorway of this room on the way to ``home`` ("" when none is known): one
    seen inside ``home`` first, then one into a room with a doorway seen inside ``home``."""
    here, rooms_of = room_guess(plan), plan["door_rooms"]
    mine = [d for d, rooms in rooms_of.items() if here in rooms and d not in plan["blocked"]]
    near = [r for rooms in rooms_of.values() if home in rooms for r in rooms if r != home]
    for ok in (lambda rooms: home in rooms, lambda rooms: any(r in near for r in rooms)):
        options = [d for d in mine if ok([r for r in rooms_of[d] if r != here])]
        if options:
            return min(options, key=lambda d: (plan["here"].get(d, math.inf), d))
    return ""


def _homing(plan: Plan, briefing: Briefing) -> bool:
    """Rule 1 of a homing scout: set a doorway towards ``home`` as the target (True), or
    False when it is home or knows no way there."""
    home = plan.setdefault("home", term_choice(plan, briefing)[0])
    if room_guess(plan) == home:
        return False
    door = _door_home(plan, home)
    plan.update(target=door, goal="door" if door else "", phase="face", tries=0)
    return bool(door)


def scout_action(
    plan: Plan, briefing: Briefing, percept: Percept, *, homing: bool = False
) -> tuple[str, str]:
    """(action, reasoning) of the room-clearing scout (``homing``: see the module docstring)."""
    plan["acted"] += 1
    if percept.step >= percept.max_steps:
        _close_room(plan)
        room, why = _home_term(plan, briefing)
        return f"Term({room})", f"Last action of the budget. {why}"
    if plan["phase"] == "sweep" and plan["turns"] < SWEEP_TURNS:
        plan["turns"] += 1
        return "Turn(Right)", f"Sweeping the room ({plan['turns']}/{SWEEP_TURNS})."
    if plan["phase"] in ("sweep", "decide"):
        _close_room(plan)
        if len(plan["visited"]) >= len(briefing.rooms):
            cleared = not plan.get("home") and _clear(plan, briefing, percept)
            if not cleared and not (homing and _homing(plan, briefing)):
                room, why = _home_term(plan, briefing)
                return f"Term({room})", why
        else:
            _choose(plan, briefing, percept)
    visible = {s.object_id for s in percept.visible}
    while plan["target"]:
        target, door = plan["target"], plan["goal"] == "door"
        if plan["tries"] <= MAX_FACE_TRIES and target in visible:
            plan["phase"] = "cross" if door else "walk"
            why = f"Advancing through {target}." if door else f"Repositioning at {target}."
            return f"Goto({target})", why
        if plan["tries"] < MAX_FACE_TRIES:
            plan["tries"] += 1
            x, z = plan["doors"][target] if door else plan["spots"][target][:2]
            return _turn_towards(percept, x, z), f"Turning towards {target}."
        if door:
            plan["blocked"].append(target)
            if "home" not in plan and _reposition(plan, [plan["doors"][target]]):
                continue
        if "home" in plan:
            _homing(plan, briefing)
        else:
            _choose(plan, briefing, percept)
    room, why = _home_term(plan, briefing)
    return f"Term({room})", f"No doorway left to try. {why}"
