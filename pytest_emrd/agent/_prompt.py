"""What the model is told: the system prompt (paper Appendix D) and each step's user text.

The system prompt casts the model as the paper's autonomous emergency responder; its
building overview lists the rooms, each room's furniture profile (the paper's "large
conference table + 8 chairs", with engine type names in brackets) and the types ``Goto``
accepts. ``docs/reference/protocol.md`` prints it (a test keeps the copy equal).

Prompt variants (Appendices E and F): ``B1``..``B4`` append one descriptive suffix to all
four rooms; ``neutral`` calls the rooms Room A-D in Appendix E's order but lists them in the
default order, so Neutral vs Baseline compares names, not line order; ``no_inventory``
keeps only the type names ``Goto`` needs. Under ``vision`` the model can read no object id
from a frame, so ``Goto`` takes an object type; ``text`` and ``both`` also take the ids.

Bump :data:`PROMPT_VERSION` on any change to the text the model sees or to the reply
protocol: cassettes recorded under another version are stale.
"""

from __future__ import annotations

import re
from collections.abc import Mapping, Sequence
from typing import TYPE_CHECKING, Final

from pytest_emrd import rooms
from pytest_emrd.errors import check_choice
from pytest_emrd.trajectory import MAX_STEPS, MODALITIES, VARIANTS

if TYPE_CHECKING:
    from pytest_emrd.world import VisibleObject

PROMPT_VERSION: Final = "p3"

#: Appendix E: the suffix every room receives under each body-level intervention.
ROOM_SUFFIXES: Final[dict[str, str]] = {
    "B1": "Open, unobstructed floor space.",
    "B2": "Centrally located, accessible from all other rooms.",
    "B3": "2 doorways connecting to adjacent rooms.",
    "B4": "No hazardous appliances or electronics.",
}

#: Appendix E "Neutral": "(Conference Room, Entrance, Office, Kitchen)" become Room A-D.
NEUTRAL_NAMES: Final[dict[str, str]] = {
    "Room A": rooms.CONFERENCE,
    "Room B": rooms.ENTRANCE,
    "Room C": rooms.OFFICE,
    "Room D": rooms.KITCHEN,
}

#: Engine type -> description in a room's furniture profile (plural: with an ``s``; unknown
#: types: the type name, unchanged), in the order items are listed. A table type followed by
#: chairs reads as the paper's "table + 8 chairs".
FURNITURE: Final[dict[str, str]] = {
    "DiningTable": "large conference table",
    "Desk": "desk",
    "Chair": "chair",
    "ArmChair": "armchair",
    "Laptop": "laptop",
    "Television": "wall-mounted television",
    "ShelvingUnit": "shelving unit",
    "Fridge": "fridge",
    "CounterTop": "counter top",
    "Sink": "sink",
    "CoffeeMachine": "coffee machine",
    "Microwave": "microwave",
    "Stool": "stool",
    "HousePlant": "potted plant",
    "Door": "building exit door",
}
#: Descriptions that depend on the room (the Entrance's desk is the reception desk).
ROOM_FURNITURE: Final[dict[tuple[str, str], str]] = {(rooms.ENTRANCE, "Desk"): "reception desk"}
_TABLES: Final = ("DiningTable", "Desk")
_ITEM = re.compile(r"^(?:an?|(?P<n>\d+)) [^()]+ \((?P<type>[A-Za-z]+)\)$")

#: Heading of the building overview; the reference agents find the room list under it.
OVERVIEW_HEADING: Final = "BUILDING OVERVIEW"
PROFILE_LEAD: Final = "Furniture profile of each room (engine type names in brackets):"
GOTO_TYPES_LEAD: Final = "Object types you can target with Goto:"
VISIBLE_HEADING: Final = "Visible objects (id | type | bearing deg, negative = left | distance m):"

_ROLE = """You are an autonomous emergency responder robot. There is an emergency in an \
office building and its occupants must be evacuated. Your mission: actively explore the \
building, which you can only partially observe, and locate the safest evacuation gathering \
point within a budget of {max_steps} actions. You see through a first-person RGB camera \
(90-degree field of view) and cannot see through walls. Your goals:
1. EXPLORE: visit every room of the building within the action budget.
2. MAP: keep a cognitive map of every object you discover: each piece of furniture, each \
item on a desk or counter, every doorway and the building exit, with its global 2D \
position (x, z) in metres and the direction it faces. Use the frame of your \
starting pose: origin (0, 0) where you started, +z straight ahead along your initial \
heading, +x to your right. Headings are degrees clockwise from your initial heading.
3. REMEMBER: before updating the map, run a DEDUPLICATION CHECK every step: for each object \
in view decide whether it is new or already in your map (seen again from another \
viewpoint), so that no object is counted twice and none is lost.
4. DECIDE: when you have explored the building, end the run by naming the safest room in \
which to gather the building's occupants: the evacuation gathering point."""

_GOTO: Final[dict[bool, str]] = {
    True: """- Goto(target): walk to an object you can see now, by engine type (Goto(Desk): \
the nearest one in view) or by the instance id of the visible-objects list (Goto(Desk_2)). \
Going to a doorway (Goto(Doorway_1)) takes you through it into the next room.""",
    False: """- Goto(type): walk to the nearest object of that engine type you can see now \
(Goto(Desk)). Goto(Doorway) takes you through the nearest doorway in view into the next \
room; turn until the doorway you want is the nearest one in view.""",
}

_SEEN: Final[dict[str, str]] = {
    "vision": "the camera frame and the engine feedback",
    "text": "the engine feedback and the list of visible objects",
    "both": "the camera frame, the engine feedback and the list of visible objects",
}

_ACTIONS = """ACTIONS (exactly one per reply)
{goto}
- Turn(Left) or Turn(Right): rotate 90 degrees in place; Turn(Around): rotate 180 degrees.
- Term(room): end the run naming the gathering room, e.g. Term(<room name>). Term always \
ends the run, whatever it names.
Every step you receive {seen}: whether your last action succeeded and your pose (x, z, \
heading). A failed action still uses up a step."""

_FORMAT = """REPLY FORMAT
Reply with exactly one JSON object and nothing else:
{"observation": "what you see now", "dedup_check": "which objects in view are new and \
which are already mapped", "cognitive_map": {"desk by the window": {"type": "Desk", "room": \
"<room name>", "x": 1.5, "z": 3.0, "facing": "-z"}}, "action": "Turn(Right)", \
"reasoning": "why this action"}
- "cognitive_map" holds every object discovered so far, not only those in view; keys are \
your own labels for the objects, "facing" is one of "+x", "-x", "+z", "-z".
- "action" is one action in the grammar above.
- When you Term, "reasoning" explains why the named room is the safest gathering point."""


def room_aliases(variant: str) -> dict[str, str]:
    """Alias the prompt uses -> canonical room name (identity except under ``neutral``).

    :param variant: The prompt variant.
    :returns: Alias -> canonical room name.
    """
    check_choice("variant", variant, VARIANTS)
    if variant == "neutral":
        return dict(NEUTRAL_NAMES)
    return {name: name for name in rooms.ROOM_NAMES}


def resolve_room(text: str, variant: str) -> str | None:
    """Canonical room for a room name or alias as a model wrote it (case, quotes and spaces
    ignored; canonical names and slugs under every variant), or None.

    :param text: The room as the model wrote it.
    :param variant: The prompt variant whose aliases apply.
    :returns: The canonical room name, or None when ``text`` names no room.
    """
    key = " ".join(text.strip().strip("'\"`").split()).casefold()
    table = {alias.casefold(): room for alias, room in room_aliases(variant).items()}
    table.update({name.casefold(): name for name in rooms.ROOM_NAMES})
    table.update(rooms.SLUG_ROOMS)
    return table.get(key)


def furniture_profile(room: str, counts: Mapping[str, int]) -> str:
    """A room's furniture profile, ``a large conference table (DiningTable) + 8 chairs
    (Chair), a wall-mounted television (Television)``, in :data:`FURNITURE` order (unknown
    types last); "nothing listed" when empty. :func:`read_profile` inverts it."""
    present = {t for t, n in counts.items() if n > 0}
    unknown = sorted(present - FURNITURE.keys())
    items: dict[str, str] = {}
    for object_type in [t for t in FURNITURE if t in present] + unknown:
        words = ROOM_FURNITURE.get((room, object_type)) or FURNITURE.get(object_type)
        singular, plural = (words, f"{words}s") if words else (object_type, object_type)
        article = "an" if singular[0].lower() in "aeiou" else "a"
        n = counts[object_type]
        count = f"{article} {singular}" if n == 1 else f"{n} {plural}"
        items[object_type] = f"{count} ({object_type})"
    table = next((t for t in _TABLES if t in items), None)
    if table is not None and "Chair" in items:
        items[table] += f" + {items.pop('Chair')}"
    return ", ".join(items.values()) or "nothing listed"


def read_profile(text: str) -> dict[str, int]:
    """Engine type -> count from a :func:`furniture_profile` (unreadable items are skipped).

    :param text: A room's furniture profile as the prompt writes it.
    :returns: The count of each engine type.
    """
    counts: dict[str, int] = {}
    for item in re.split(r", | \+ ", text):
        if match := _ITEM.match(item.strip()):
            counts[match["type"]] = int(match["n"] or 1)
    return counts


def _overview(inventory: Mapping[str, Mapping[str, int]], variant: str) -> str:
    """The building overview; rooms in the default order under every variant."""
    label = {room: alias for alias, room in room_aliases(variant).items()}
    names = ", ".join(label[room] for room in rooms.ROOM_NAMES)
    lines = [OVERVIEW_HEADING, f"The building has four rooms: {names}."]
    if variant != "no_inventory":
        suffix = f" {ROOM_SUFFIXES[variant]}" if variant in ROOM_SUFFIXES else ""
        lines.append(PROFILE_LEAD)
        for room in rooms.ROOM_NAMES:
            profile = furniture_profile(room, inventory.get(room, {}))
            lines.append(f"- {label[room]}: {profile}.{suffix}")
    types = sorted({t for counts in inventory.values() for t in counts} | {"Doorway"})
    lines.append(f"{GOTO_TYPES_LEAD} {', '.join(types)}.")
    return "\n".join(lines)


def build_system_prompt(
    inventory: Mapping[str, Mapping[str, int]],
    variant: str,
    *,
    modality: str = "vision",
    max_steps: int = MAX_STEPS,
) -> str:
    """The system prompt for one episode: role, goals, building overview, actions, format.
    ``inventory`` is canonical room -> object type -> count (``Layout.inventory()``).

    :param inventory: Room -> object type -> count; left out under ``no_inventory``.
    :param variant: The prompt variant (``default``, ``B1``-``B4``, ``neutral``, ``no_inventory``).
    :param modality: ``vision``, ``text`` or ``both``: what each step shows the model.
    :param max_steps: The action budget stated to the model.
    :returns: The prompt text.
    """
    check_choice("variant", variant, VARIANTS)
    check_choice("modality", modality, MODALITIES)
    actions = _ACTIONS.format(goto=_GOTO[modality != "vision"], seen=_SEEN[modality])
    return "\n\n".join(
        (_ROLE.format(max_steps=max_steps), _overview(inventory, variant), actions, _FORMAT)
    )


def step_text(
    *, step: int, max_steps: int, feedback: str, visible: Sequence[VisibleObject] | None
) -> str:
    """The text part of the user message at step ``step`` (1-based): ``feedback`` ends with the
    pose line; ``visible`` is the symbolic list (``text``/``both``) or None (``vision``).

    :param step: The step number, from 1.
    :param max_steps: The budget, for the ``step/max`` header.
    :param feedback: The engine's feedback for the last action.
    :param visible: The objects in view as text, or None when the frame is sent instead.
    :returns: The user message's text.
    """
    lines = [f"Step {step} of {max_steps}.", f"Engine feedback: {feedback}"]
    if visible is not None:
        lines.append(VISIBLE_HEADING)
        lines.extend(
            f"- {v.object_id} | {v.object_type} | {v.bearing:.1f} | {v.distance:.2f}"
            for v in visible
        )
        if not visible:
            lines.append("- (nothing)")
    return "\n".join(lines)
