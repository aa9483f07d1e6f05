"""What the model is told: the system prompt (paper Appendix D) and each step's user text.

Prompt variants (Appendices E and F):

* ``default`` — room names and furniture inventory, no descriptive suffix.
* ``B1``..``B4`` — the same descriptive suffix appended to all four rooms, neutralising
  one feature as a discriminator (open space, centrality, exits, hazards).
* ``neutral`` — rooms called Room A-D; Room A is the physical Conference Room, then
  Room B = Office, Room C = Kitchen, Room D = Entrance.
* ``no_inventory`` — the engine's type names (needed for ``Goto``) are kept; counts, the
  room mapping and furniture descriptions are removed.

Bump :data:`PROMPT_VERSION` on any change to the text the model sees or to the reply
protocol: cassettes recorded under another version are stale.
"""

from __future__ import annotations

from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Final

from pytest_emrd import rooms
from pytest_emrd.errors import check_choice
from pytest_emrd.trajectory import MAX_STEPS, VARIANTS, Pose

if TYPE_CHECKING:
    from pytest_emrd.world._model import VisibleObject

PROMPT_VERSION: Final = "p1"

#: Appendix E: the suffix every room receives under each body-level intervention.
ROOM_SUFFIXES: Final[dict[str, str]] = {
    "B1": "Open, unobstructed floor space.",
    "B2": "Centrally located, accessible from all other rooms.",
    "B3": "2 doorways connecting to adjacent rooms.",
    "B4": "No hazardous appliances or electronics.",
}

#: Appendix E "Neutral": generic label -> physical room (Room A is the Conference Room).
NEUTRAL_NAMES: Final[dict[str, str]] = {
    "Room A": rooms.CONFERENCE,
    "Room B": rooms.OFFICE,
    "Room C": rooms.KITCHEN,
    "Room D": rooms.ENTRANCE,
}

#: Heading of the building overview; the reference agents find the room list under it.
OVERVIEW_HEADING: Final = "BUILDING OVERVIEW"
GOTO_TYPES_LEAD: Final = "Object types you can target with Goto:"
VISIBLE_HEADING: Final = "Visible objects (id | type | bearing deg, negative = left | distance m):"

_ROLE = """You are an autonomous emergency responder robot inside an office building during \
an emergency. You see the building through a first-person camera (90-degree field of view) \
and cannot see through walls. You have a budget of {max_steps} actions. Your goals:
1. EXPLORE: visit every room of the building within the action budget.
2. MAP: keep a cognitive map of every salient object you discover, with its global 2D \
position (x, z) in metres and the direction it faces. Use the frame of your starting pose: \
origin (0, 0) where you started, +z straight ahead along your initial heading, +x to your \
right. Headings are degrees clockwise from your initial heading.
3. REMEMBER: before updating the map, run a DEDUPLICATION CHECK every step: for each object \
in view decide whether it is new or already in your map (seen again from another \
viewpoint), so that no object is counted twice and none is lost.
4. DECIDE: when you have explored the building, end the run by naming the safest room in \
which to gather the building's occupants."""

_ACTIONS = """ACTIONS (exactly one per reply)
- Goto(target): walk to an object you can see now, by type (Goto(Desk)) or instance id \
(Goto(Desk_2)). Going to a doorway (Goto(Doorway_1)) takes you through it into the next room.
- Turn(Left) or Turn(Right): rotate 90 degrees in place; Turn(Around): rotate 180 degrees.
- Term(room): end the run naming the gathering room, e.g. Term(<room name>).
Every step you receive the camera frame and the engine feedback: whether your last action \
succeeded and your pose (x, z, heading). A failed action still uses up a step."""

_FORMAT = """REPLY FORMAT
Reply with exactly one JSON object and nothing else:
{"observation": "what you see now", "dedup_check": "which objects in view are new and \
which are already mapped", "cognitive_map": {"Desk_1": {"type": "Desk", "room": \
"<room name>", "x": 1.5, "z": 3.0, "facing": "-z"}}, "action": "Turn(Right)", \
"reasoning": "why this action"}
- "cognitive_map" holds every object discovered so far, not only those in view; keys are \
the object labels, "facing" is one of "+x", "-x", "+z", "-z".
- "action" is one action in the grammar above.
- When you Term, "reasoning" explains why the named room is the safest gathering point."""


def room_aliases(variant: str) -> dict[str, str]:
    """Alias the prompt uses -> canonical room name (identity except under ``neutral``)."""
    check_choice("variant", variant, VARIANTS)
    if variant == "neutral":
        return dict(NEUTRAL_NAMES)
    return {name: name for name in rooms.ROOM_NAMES}


def resolve_room(text: str, variant: str) -> str | None:
    """Canonical room for a room name or alias as a model wrote it, or None.

    Case, surrounding quotes and spaces are ignored; canonical names and slugs are
    accepted under every variant (a model may name the physical room it saw).
    """
    key = " ".join(text.strip().strip("'\"`").split()).casefold()
    table = {alias.casefold(): room for alias, room in room_aliases(variant).items()}
    table.update({name.casefold(): name for name in rooms.ROOM_NAMES})
    table.update(rooms.SLUG_ROOMS)
    return table.get(key)


def _room_order(variant: str) -> list[tuple[str, str]]:
    """(label shown, canonical room) in prompt order."""
    aliases = room_aliases(variant)
    return sorted(aliases.items()) if variant == "neutral" else list(aliases.items())


def _overview(inventory: Mapping[str, Mapping[str, int]], variant: str) -> str:
    order = _room_order(variant)
    lines = [OVERVIEW_HEADING, f"The building has four rooms: {', '.join(a for a, _ in order)}."]
    if variant == "no_inventory":
        types = sorted({t for counts in inventory.values() for t in counts} | {"Doorway"})
        lines.append(f"{GOTO_TYPES_LEAD} {', '.join(types)}.")
        return "\n".join(lines)
    suffix = f" {ROOM_SUFFIXES[variant]}" if variant in ROOM_SUFFIXES else ""
    for label, room in order:
        counts = inventory.get(room, {})
        items = ", ".join(f"{n} {t}" for t, n in sorted(counts.items())) or "nothing listed"
        lines.append(f"- {label}: {items}.{suffix}")
    return "\n".join(lines)


def build_system_prompt(
    inventory: Mapping[str, Mapping[str, int]], variant: str, *, max_steps: int = MAX_STEPS
) -> str:
    """The system prompt for one episode: role, goals, building overview, actions, format.

    ``inventory`` is room -> object type -> count (``Layout.inventory()``, doorways
    excluded); rooms are the canonical names whatever the variant.
    """
    check_choice("variant", variant, VARIANTS)
    return "\n\n".join(
        (_ROLE.format(max_steps=max_steps), _overview(inventory, variant), _ACTIONS, _FORMAT)
    )


def step_text(
    *,
    step: int,
    max_steps: int,
    feedback: str,
    pose: Pose,
    visible: Sequence[VisibleObject] | None,
) -> str:
    """The text part of the user message shown at step ``step`` (1-based).

    ``visible`` is the symbolic list (``text``/``both`` modality) or None (``vision``).
    """
    lines = [
        f"Step {step} of {max_steps}.",
        f"Engine feedback: {feedback}",
        f"Pose: x={pose.x:.2f} z={pose.z:.2f} heading={pose.heading:.0f}",
    ]
    if visible is not None:
        lines.append(VISIBLE_HEADING)
        lines.extend(
            f"- {v.object_id} | {v.object_type} | {v.bearing:.1f} | {v.distance:.2f}"
            for v in visible
        )
        if not visible:
            lines.append("- (nothing)")
    return "\n".join(lines)
