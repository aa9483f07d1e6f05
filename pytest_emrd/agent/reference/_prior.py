"""The ``prior`` policy: a decision from the prompt alone, with zero spatial evidence.

At its first step ``prior`` reads the visible list only to infer the room it stands in
(the same inventory vote every scripted agent casts), keeps an empty cognitive map
(planted memory ``none``) and terminates naming the room whose inventory lists the most
seats (chairs, sofas, stools) other than the room it is in: the furniture prior the paper
found behind the Conference Room choice. It never moves and maps nothing, so the chosen
room is never visited and the map holds none of its objects (Never-Visited and Any-Bias
100 %, FPSG 0). With nothing identifiable in view it cannot exclude its own room and
chooses among all four.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Any, Final

from pytest_emrd.agent.reference._perceive import room_guess
from pytest_emrd.agent.reference._read import Briefing, Percept

SEATS: Final = ("Chair", "Sofa", "Stool")


def seats(counts: Mapping[str, int]) -> int:
    """Seats an inventory line lists (every type whose name contains Chair, Sofa or Stool)."""
    return sum(n for t, n in counts.items() if any(s in t for s in SEATS))


def prior_action(plan: dict[str, Any], briefing: Briefing, percept: Percept) -> tuple[str, str]:
    """(action, reasoning) of the prior agent: ``Term`` at once, naming another room."""
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
