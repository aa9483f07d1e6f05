"""The furniture catalogue: one row per kind of object the built-in office contains.

Each kind names its AI2-THOR ``objectType`` (what ids, prompts and the ai2thor backend use),
its memory category, its size ``width x depth x height`` in metres, the height it stands at
and its baseline colour per material role (the renderer composes each kind from boxes, one
role per box). Landmarks are the doorways and the building exit; salient objects are large
furniture a responder would use to orient; clutter is small or movable. An object's *front*
faces the heading given by its ``rotation`` (a chair's front faces its desk or table).
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

RGB = tuple[int, int, int]


@dataclass(frozen=True)
class Kind:
    """One row of the catalogue."""

    name: str
    object_type: str
    category: str
    width: float
    depth: float
    height: float
    colors: Mapping[str, RGB]
    """Material role -> baseline colour; the first role is the object's main colour."""
    elevation: float = 0.0
    """Height of the base above the floor (items standing on a desk or counter)."""


DESK_HEIGHT: Final = 0.76
COUNTER_HEIGHT: Final = 0.92
DOOR_HEIGHT: Final = 2.1
WALL_HEIGHT: Final = 2.7

_WOOD: Final[RGB] = (150, 108, 68)
_DARK_WOOD: Final[RGB] = (92, 60, 40)
_METAL: Final[RGB] = (88, 90, 96)
_SCREEN: Final[RGB] = (22, 26, 34)

_ROWS: Final = (
    # name, objectType, category, width, depth, height, elevation
    ("Doorway", "Doorway", "landmark", 1.0, 0.1, DOOR_HEIGHT, 0.0),
    ("Door", "Door", "landmark", 1.0, 0.06, DOOR_HEIGHT, 0.0),
    ("Desk", "Desk", "salient", 1.4, 0.7, DESK_HEIGHT, 0.0),
    ("ReceptionDesk", "Desk", "salient", 1.8, 0.8, 1.05, 0.0),
    ("DiningTable", "DiningTable", "salient", 3.0, 1.1, DESK_HEIGHT, 0.0),
    ("ShelvingUnit", "ShelvingUnit", "salient", 1.0, 0.4, 1.8, 0.0),
    ("Television", "Television", "salient", 1.4, 0.4, 1.35, 0.0),
    ("Fridge", "Fridge", "salient", 0.8, 0.75, 1.9, 0.0),
    ("CounterTop", "CounterTop", "salient", 2.0, 0.65, COUNTER_HEIGHT, 0.0),
    ("ArmChair", "ArmChair", "salient", 0.85, 0.85, 0.9, 0.0),
    ("Chair", "Chair", "clutter", 0.5, 0.5, 0.92, 0.0),
    ("Stool", "Stool", "clutter", 0.4, 0.4, 0.7, 0.0),
    ("HousePlant", "HousePlant", "clutter", 0.45, 0.45, 1.05, 0.0),
    ("Laptop", "Laptop", "clutter", 0.34, 0.24, 0.24, DESK_HEIGHT),
    ("Sink", "Sink", "clutter", 0.6, 0.45, 0.25, COUNTER_HEIGHT),
    ("Microwave", "Microwave", "clutter", 0.5, 0.36, 0.3, COUNTER_HEIGHT),
    ("CoffeeMachine", "CoffeeMachine", "clutter", 0.26, 0.3, 0.38, COUNTER_HEIGHT),
)
_COLORS: Final[Mapping[str, Mapping[str, RGB]]] = {
    "Doorway": {"frame": (122, 86, 52)},
    "Door": {
        "panel": (104, 118, 140),
        "frame": (70, 70, 76),
        "bar": (205, 205, 210),
        "sign": (20, 175, 70),
        "sign_text": (235, 245, 235),
    },
    "Desk": {"top": _WOOD, "leg": _METAL},
    "ReceptionDesk": {"front": (210, 200, 185), "counter": _DARK_WOOD, "leg": _METAL},
    "DiningTable": {"top": _DARK_WOOD, "leg": (60, 60, 66)},
    "ShelvingUnit": {
        "frame": (120, 84, 52),
        "book_a": (165, 45, 40),
        "book_b": (40, 90, 155),
        "book_c": (205, 170, 60),
    },
    "Television": {"stand": (64, 48, 38), "screen": (18, 18, 22), "display": (34, 52, 86)},
    "Fridge": {"body": (228, 230, 232), "handle": (110, 112, 118), "seam": (140, 142, 148)},
    "CounterTop": {"cabinet": (232, 226, 210), "top": (66, 66, 72), "handle": (120, 120, 126)},
    "ArmChair": {"fabric": (150, 62, 50), "leg": (50, 40, 32)},
    "Chair": {"fabric": (44, 72, 128), "leg": (56, 56, 60)},
    "Stool": {"seat": (176, 44, 40), "leg": _METAL},
    "HousePlant": {"leaves": (48, 132, 56), "pot": (172, 92, 52), "leaves_dark": (34, 100, 44)},
    "Laptop": {"body": (172, 172, 178), "screen": _SCREEN},
    "Sink": {"basin": (178, 184, 190), "tap": (200, 200, 206)},
    "Microwave": {"body": (62, 62, 68), "window": (14, 14, 18), "panel": (160, 160, 164)},
    "CoffeeMachine": {"body": (30, 30, 32), "accent": (190, 40, 40)},
}
KINDS: Final[Mapping[str, Kind]] = {
    row[0]: Kind(*row[:6], colors=_COLORS[row[0]], elevation=row[6]) for row in _ROWS
}

#: objectType -> category, for every type the built-in office uses.
CATEGORY_OF: Final[Mapping[str, str]] = {k.object_type: k.category for k in KINDS.values()}

#: objectType -> material role -> baseline colour, merged over the kinds of that type (the
#: reception desk adds its front panel and counter to the office desk's materials).
COLORS_OF: Final[Mapping[str, Mapping[str, RGB]]] = {
    t: {role: c for k in KINDS.values() if k.object_type == t for role, c in k.colors.items()}
    for t in CATEGORY_OF
}

#: Room surface colours: walls and floors per room, ceiling and skirting shared.
WALL_COLORS: Final[Mapping[str, RGB]] = {
    "Office": (206, 200, 184),
    "Conference Room": (186, 198, 212),
    "Kitchen": (218, 216, 196),
    "Entrance": (204, 188, 170),
}
FLOOR_COLORS: Final[Mapping[str, RGB]] = {
    "Office": (92, 98, 112),
    "Conference Room": (132, 100, 78),
    "Kitchen": (196, 196, 190),
    "Entrance": (150, 140, 124),
}
CEILING_COLOR: Final[RGB] = (236, 236, 232)
SKIRTING_COLOR: Final[RGB] = (78, 72, 66)
