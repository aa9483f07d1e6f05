"""Vendored look-up tables for turning an EMRD layout into a ProcTHOR house.

ProcTHOR knows four room types and instantiates furniture from prefab asset ids. The
tables below pick one asset per AI2-THOR ``objectType`` the EMRD office uses, so the
same layout always produces the same house. They are deliberately small and explicit:
a layout object whose type is missing here is a configuration error (see
:func:`asset_for`), never a silent guess. Callers with a different THOR build pass
their own ``asset_ids`` mapping to :func:`pytest_emrd.world.thor.build_house`.
"""

from __future__ import annotations

from collections.abc import Mapping
from typing import Final

from pytest_emrd.errors import ConfigError
from pytest_emrd.rooms import CONFERENCE, ENTRANCE, KITCHEN, OFFICE

SCHEMA: Final = "1.0.0"
"""ProcTHOR house schema version this package writes."""

#: EMRD room -> the ProcTHOR ``roomType`` it is built as (THOR knows Kitchen, LivingRoom,
#: Bedroom and Bathroom only; our own names are kept in the house metadata).
THOR_ROOM_TYPES: Final[Mapping[str, str]] = {
    OFFICE: "LivingRoom",
    CONFERENCE: "LivingRoom",
    KITCHEN: "Kitchen",
    ENTRANCE: "LivingRoom",
}

#: AI2-THOR ``objectType`` -> ProcTHOR prefab ``assetId``.
ASSET_IDS: Final[Mapping[str, str]] = {
    "ArmChair": "Armchair_208_1",
    "Chair": "Chair_007_1",
    "CoffeeMachine": "Coffee_Machine_1",
    "CounterTop": "Countertop_I_8x2",
    "Desk": "Desk_310_1",
    "DiningTable": "Dining_Table_16_1",
    "Door": "Doorway_1",
    "Doorway": "Doorway_1",
    "Fridge": "Fridge_1",
    "HousePlant": "Houseplant_1",
    "Laptop": "Laptop_1",
    "Microwave": "Microwave_1",
    "ShelvingUnit": "Shelving_Unit_307_1",
    "Sink": "Sink_1",
    "Stool": "Stool_1",
    "Television": "Television_1",
}

DOOR_TYPES: Final[frozenset[str]] = frozenset({"Doorway", "Door"})
"""Object types built as wall holes (``doors``), not as free-standing objects."""

FLOOR_MATERIAL: Final = "DarkWoodFloors"
CEILING_MATERIAL: Final = "ps_mat"
SKYBOX_ID: Final = "Sky1"

WALL_COLOR: Final[tuple[float, float, float]] = (0.93, 0.92, 0.89)
"""Baseline wall albedo (warm white)."""


def asset_for(object_type: str, table: Mapping[str, str]) -> str:
    """The ``assetId`` for ``object_type``, or :class:`ConfigError` naming the fix."""
    try:
        return table[object_type]
    except KeyError:
        raise ConfigError(
            f"object_type={object_type!r} has no ProcTHOR asset in the vendored table; "
            "pass asset_ids={..., " + repr(object_type) + ": '<assetId>'} to build_house "
            "with an asset id from your THOR build."
        ) from None
