"""Low-poly box compositions: how each kind of object looks to the ray-caster.

Every object is a few axis-aligned boxes in its own frame (``u`` right, ``v`` forward,
``y`` up from its base), each with a material role whose colour the palette supplies,
listed bottom-up; a box marked ``facing`` (a screen, a handle, a sign) is drawn only from
that side. A builder takes the object's half width ``hw``, half depth ``hd`` and height ``h``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, replace

from pytest_emrd.world._catalog import DOOR_HEIGHT, WALL_HEIGHT
from pytest_emrd.world._model import WorldObject


@dataclass(frozen=True)
class Box:
    u0: float
    u1: float
    v0: float
    v1: float
    y0: float
    y1: float
    role: str
    """Material role: a key of the kind's colours, or ``wall`` for the wall colour of the
    room the box stands in (the two halves of a doorway's lintel differ)."""
    facing: float = 0.0
    """+1 drawn only from the front side, -1 only from the back, 0 always."""


def _full(hw: float, hd: float, y0: float, y1: float, role: str) -> Box:
    """A box over the whole footprint from ``y0`` to ``y1``."""
    return Box(-hw, hw, -hd, hd, y0, y1, role)


def _mirrored(left: Box) -> list[Box]:
    """``left`` and its mirror image across the object's centre line (a pair of legs)."""
    return [left, replace(left, u0=-left.u1, u1=-left.u0)]


def _legs(hw: float, hd: float, top: float, size: float, inset: float, role: str) -> list[Box]:
    hu, hv = hw - inset, hd - inset
    us, vs = ((-hu, -hu + size), (hu - size, hu)), ((-hv, -hv + size), (hv - size, hv))
    return [Box(u0, u1, v0, v1, 0.0, top, role) for u0, u1 in us for v0, v1 in vs]


def _desk(hw: float, hd: float, h: float) -> list[Box]:
    if h > 0.9:  # reception desk: a tall panel towards the room, a work top behind it
        return [
            *_mirrored(Box(-hw, -hw + 0.04, -hd, hd - 0.06, 0.0, 0.72, "leg")),
            Box(-hw, hw, -hd, hd - 0.06, 0.72, 0.76, "counter"),
            Box(-hw, hw, hd - 0.06, hd, 0.0, h - 0.03, "front"),
            Box(-hw, hw, hd - 0.22, hd, h - 0.03, h, "counter"),
        ]
    return [
        *_mirrored(Box(-hw + 0.03, -hw + 0.07, -hd + 0.03, hd - 0.03, 0.0, h - 0.04, "leg")),
        Box(-hw + 0.07, hw - 0.07, -hd + 0.03, -hd + 0.06, 0.3, h - 0.04, "leg"),
        _full(hw, hd, h - 0.04, h, "top"),
    ]


def _table(hw: float, hd: float, h: float) -> list[Box]:
    u = hw - 0.45
    legs = [
        Box(s * u - 0.05, s * u + 0.05, -hd + 0.2, hd - 0.2, 0.0, h - 0.05, "leg") for s in (-1, 1)
    ]
    return [*legs, _full(hw, hd, h - 0.05, h, "top")]


def _chair(hw: float, hd: float, h: float) -> list[Box]:
    return [
        *_legs(hw, hd, 0.44, 0.04, 0.03, "leg"),
        Box(-hw, hw, -hd, hd, 0.44, 0.5, "fabric"),
        Box(-hw + 0.02, hw - 0.02, -hd, -hd + 0.06, 0.5, h, "fabric"),
    ]


def _stool(hw: float, hd: float, h: float) -> list[Box]:
    return [*_legs(hw, hd, 0.64, 0.03, 0.05, "leg"), _full(hw, hd, 0.64, h, "seat")]


def _armchair(hw: float, hd: float, h: float) -> list[Box]:
    return [
        *_legs(hw, hd, 0.1, 0.05, 0.04, "leg"),
        Box(-hw, hw, -hd, hd, 0.1, 0.45, "fabric"),
        Box(-hw, hw, -hd, -hd + 0.2, 0.45, h, "fabric"),
        *_mirrored(Box(-hw, -hw + 0.14, -hd + 0.2, hd, 0.45, 0.66, "fabric")),
    ]


_BOOKS = ((0.08, 0.22, "book_a"), (0.26, 0.18, "book_b"), (0.5, 0.26, "book_c"))


def _shelf(hw: float, hd: float, h: float) -> list[Box]:
    boards = (0.05, 0.47, 0.9, 1.33, h - 0.03)
    boxes = [Box(-hw, hw, -hd, -hd + 0.02, 0.0, h, "frame")]
    for i, y in enumerate(boards):
        boxes.append(Box(-hw + 0.03, hw - 0.03, -hd, hd, y, y + 0.03, "frame"))
        if i < len(boards) - 1:
            for j, (start, span, role) in enumerate(_BOOKS):
                u0 = -hw + 0.05 + ((start + 0.11 * i) % 0.62)
                tall = 0.24 + 0.04 * ((i + j) % 3)
                boxes.append(Box(u0, u0 + span, -hd + 0.03, hd - 0.08, y + 0.03, y + tall, role))
    return [*boxes, *_mirrored(Box(-hw, -hw + 0.03, -hd, hd, 0.0, h, "frame"))]


def _television(hw: float, hd: float, h: float) -> list[Box]:
    return [
        Box(-hw, hw, -hd, hd, 0.0, 0.5, "stand"),
        Box(-0.06, 0.06, -0.06, 0.02, 0.5, 0.6, "screen"),
        Box(-hw + 0.08, hw - 0.08, -0.06, 0.0, 0.6, h, "screen"),
        Box(-hw + 0.12, hw - 0.12, 0.0, 0.01, 0.64, h - 0.04, "display", 1.0),
    ]


def _fridge(hw: float, hd: float, h: float) -> list[Box]:
    return [
        _full(hw, hd, 0.0, h, "body"),
        Box(-hw, hw, hd, hd + 0.005, 1.2, 1.23, "seam", 1.0),
        Box(hw - 0.12, hw - 0.08, hd, hd + 0.05, 0.65, 1.12, "handle", 1.0),
        Box(hw - 0.12, hw - 0.08, hd, hd + 0.05, 1.3, 1.6, "handle", 1.0),
    ]


def _counter(hw: float, hd: float, h: float) -> list[Box]:
    handles = [
        Box(u - 0.08, u + 0.08, hd - 0.03, hd - 0.01, h - 0.2, h - 0.17, "handle", 1.0)
        for u in (-hw + 0.3 + 0.6 * k for k in range(int(2 * hw / 0.6)))
    ]
    return [
        Box(-hw, hw, -hd, hd - 0.03, 0.0, h - 0.04, "cabinet"),
        *handles,
        _full(hw, hd, h - 0.04, h, "top"),
    ]


def _sink(hw: float, hd: float, h: float) -> list[Box]:
    return [
        Box(-hw, hw, -hd, hd, 0.0, 0.012, "basin"),
        Box(-0.02, 0.02, -hd, -hd + 0.05, 0.0, h, "tap"),
        Box(-0.02, 0.02, -hd, -hd + 0.2, h - 0.03, h, "tap"),
    ]


def _microwave(hw: float, hd: float, h: float) -> list[Box]:
    return [
        _full(hw, hd, 0.0, h, "body"),
        Box(-hw + 0.04, hw - 0.15, hd, hd + 0.005, 0.05, h - 0.05, "window", 1.0),
        Box(hw - 0.13, hw - 0.03, hd, hd + 0.005, 0.05, h - 0.05, "panel", 1.0),
    ]


def _coffee(hw: float, hd: float, h: float) -> list[Box]:
    return [
        _full(hw, hd, 0.0, 0.04, "body"),
        Box(-hw, hw, -hd, -hd + 0.13, 0.04, h - 0.08, "body"),
        Box(-0.06, 0.06, -0.02, 0.09, 0.04, 0.17, "accent"),
        _full(hw, hd, h - 0.08, h, "body"),
    ]


def _laptop(hw: float, hd: float, h: float) -> list[Box]:
    return [
        _full(hw, hd, 0.0, 0.02, "body"),
        Box(-hw, hw, -hd, -hd + 0.015, 0.02, h, "screen"),
        Box(-hw, hw, -hd - 0.004, -hd, 0.02, h, "body", -1.0),
    ]


def _plant(hw: float, hd: float, h: float) -> list[Box]:
    return [
        Box(-0.15, 0.15, -0.15, 0.15, 0.0, 0.35, "pot"),
        Box(-hw, hw, -hw, hw, 0.35, 0.8, "leaves"),
        Box(-0.16, 0.16, -0.16, 0.16, 0.8, h, "leaves_dark"),
    ]


def _doorway(hw: float, hd: float, h: float) -> list[Box]:
    top = DOOR_HEIGHT  # the top of the gap in the wall
    return [
        *_mirrored(Box(-hw - 0.07, -hw, -0.08, 0.08, 0.0, top + 0.07, "frame")),
        Box(-hw, hw, -0.08, 0.08, top, top + 0.07, "frame"),
        Box(-hw, hw, -0.005, 0.0, top + 0.07, WALL_HEIGHT, "wall"),
        Box(-hw, hw, 0.0, 0.005, top + 0.07, WALL_HEIGHT, "wall"),
    ]


def _door(hw: float, hd: float, h: float) -> list[Box]:
    return [
        Box(-hw + 0.06, hw - 0.06, -hd, hd, 0.0, h - 0.06, "panel"),
        *_mirrored(Box(-hw, -hw + 0.06, -hd, hd + 0.03, 0.0, h, "frame")),
        Box(-hw, hw, -hd, hd + 0.03, h - 0.06, h, "frame"),
        Box(-hw + 0.16, hw - 0.16, hd, hd + 0.05, 0.95, 1.02, "bar", 1.0),
        Box(-0.25, 0.25, -hd, hd + 0.06, h + 0.15, h + 0.37, "sign"),
        Box(-0.17, 0.17, hd + 0.06, hd + 0.065, h + 0.21, h + 0.31, "sign_text", 1.0),
    ]


_BUILDERS: dict[str, Callable[[float, float, float], list[Box]]] = {
    "Desk": _desk,
    "DiningTable": _table,
    "Chair": _chair,
    "Stool": _stool,
    "ArmChair": _armchair,
    "ShelvingUnit": _shelf,
    "Television": _television,
    "Fridge": _fridge,
    "CounterTop": _counter,
    "Sink": _sink,
    "Microwave": _microwave,
    "CoffeeMachine": _coffee,
    "Laptop": _laptop,
    "HousePlant": _plant,
    "Doorway": _doorway,
    "Door": _door,
}


def boxes_of(obj: WorldObject) -> list[Box]:
    """The boxes that draw ``obj``, in its own frame; a plain box for an unknown type."""
    builder = _BUILDERS.get(obj.object_type, lambda hw, hd, h: [_full(hw, hd, 0.0, h, "main")])
    return builder(obj.width / 2, obj.depth / 2, obj.height)
