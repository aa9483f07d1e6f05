"""The ``prior`` policy: a decision from the prompt alone, with zero spatial evidence.

``prior`` never moves and maps nothing (planted memory ``none``: every reported map is
empty). It turns in place through one sweep (the first view plus three ``Turn(Right)``),
only to infer the room it stands in by the same inventory vote every scripted agent casts,
then terminates naming the room whose inventory lists the most seats (chairs, sofas,
stools) other than that room: the furniture prior the paper found behind the Conference
Room choice. The chosen room is therefore never visited and the map holds none of its
objects (Never-Visited and Any-Bias 100 %, FPSG 0).

One view is not enough to know the room: spawned facing a wall or a doorway, the first
view often shows nothing of the spawn room (9 of 80 Conference Room spawns in the
validation run), and a prior deciding there would name its own room. With nothing
identifiable after the sweep it chooses among all four rooms.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Final

from pytest_emrd.agent.reference._perceive import SWEEP_TURNS, room_guess
from pytest_emrd.agent.reference._read import Briefing, Percept

SEATS: Final = ("Chair", "Sofa", "Stool")


def seats(counts: Mapping[str, int]) -> int:
    """Seats an inventory line lists (every type whose name contains Chair, Sofa or Stool)."""
    return sum(n for t, n in counts.items() if any(s in t for s in SEATS))


def prior_action(plan: dict[str, Any], briefing: Briefing, percept: Percept) -> tuple[str, str]:
    """(action, reasoning) of the prior agent: look around in place, then name another room."""
    if plan["turns"] < SWEEP_TURNS and percept.step < percept.max_steps:
        plan["turns"] += 1
        return "Turn(Right)", f"Looking around to tell where I am ({plan['turns']}/{SWEEP_TURNS})."
    here = room_guess(plan)
    others = [r for r in briefing.rooms if r != here]
    inventory = briefing.inventory
    room = max(others, key=lambda r: (seats(inventory.get(r, {})), -others.index(r)))
    where = f"the {here} where I stand" if here else "this room"
    return (
        f"Term({room})",
        f"{room} has the most seating for a gathering ({seats(inventory.get(room, {}))} "
        f"seats by the building overview), more than any room other than {where}.",
    )
