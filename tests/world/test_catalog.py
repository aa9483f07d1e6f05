"""The catalogue and the box compositions agree: every material has its colour."""

from __future__ import annotations

import pytest

from pytest_emrd.world import KINDS, Layout, generate_layout
from pytest_emrd.world._catalog import COLORS_OF
from pytest_emrd.world._shapes import boxes_of


def test_kinds_of_one_type_never_disagree_on_a_colour() -> None:
    for kind in KINDS.values():
        for role, color in kind.colors.items():
            assert COLORS_OF[kind.object_type][role] == color, (kind.name, role)


@pytest.mark.parametrize("seed", [0, 7])
def test_every_box_role_has_a_catalogue_colour(seed: int) -> None:
    layout: Layout = generate_layout(seed)
    for obj in layout.objects:
        boxes = boxes_of(obj)
        assert boxes, obj.object_id
        for box in boxes:
            assert box.role == "wall" or box.role in COLORS_OF[obj.object_type], (obj, box)
            assert box.u0 < box.u1 and box.v0 < box.v1 and box.y0 < box.y1, (obj, box)


def test_categories_follow_the_paper() -> None:
    by_category: dict[str, set[str]] = {}
    for kind in KINDS.values():
        by_category.setdefault(kind.category, set()).add(kind.object_type)
    assert by_category["landmark"] == {"Doorway", "Door"}
    assert {
        "Desk",
        "DiningTable",
        "Fridge",
        "CounterTop",
        "ShelvingUnit",
        "Television",
        "ArmChair",
    } <= by_category["salient"]
    assert {"Chair", "Laptop", "HousePlant", "Microwave", "CoffeeMachine", "Stool"} <= (
        by_category["clutter"]
    )
