"""ProcTHOR assets for the EMRD office: which prefab stands in for which layout object.

``assets.json`` holds every asset of the office's object types with its bounding box,
copied from allenai/procthor ``procthor/databases/asset-database.json`` at commit
53d5bd4c8c96a699e6a615dc390abb670cc9d353. THOR skips an id missing from its database
silently, so an id this package emits must exist. How :func:`choose_asset` picks:
``docs/ai2thor.md``.
"""

from __future__ import annotations

import json
from collections.abc import Mapping
from dataclasses import dataclass
from functools import cache
from importlib import resources
from typing import Final

from pytest_emrd.errors import ConfigError
from pytest_emrd.rooms import CONFERENCE, ENTRANCE, KITCHEN, OFFICE

SCHEMA: Final = "1.0.0"
"""ProcTHOR house schema version this package writes."""

#: EMRD room -> the ProcTHOR ``roomType`` it is built as (our names go in the metadata).
THOR_ROOM_TYPES: Final[Mapping[str, str]] = {
    OFFICE: "LivingRoom",
    CONFERENCE: "LivingRoom",
    KITCHEN: "Kitchen",
    ENTRANCE: "LivingRoom",
}

#: EMRD ``objectType`` -> the asset-database type its assets come from, where they differ.
ASSET_TYPES: Final[Mapping[str, str]] = {"Door": "Doorway"}

DOOR_TYPES: Final[frozenset[str]] = frozenset({"Doorway", "Door"})
"""Object types built as wall holes (``doors``), not as free-standing objects."""

FLOOR_MATERIAL: Final = "DarkWoodFloors"
CEILING_MATERIAL: Final = "ps_mat"
SKYBOX_ID: Final = "Sky1"
"""procthor ``skyboxes.json``: a ``Midday`` sky (the baseline's ambient light)."""
DIM_SKYBOX_ID: Final = "Sky2Dusk"
"""A ``BlueHour`` sky, the darkest procthor lights a house with: THOR takes the ambient
light from the skybox, so ``low_light`` switches to it."""
WALL_COLOR: Final[tuple[float, float, float]] = (0.93, 0.92, 0.89)


@dataclass(frozen=True)
class Asset:
    """One ProcTHOR prefab and its bounding box (metres, the asset's own axes)."""

    asset_id: str
    object_type: str
    """Its type in the asset database (``Doorway`` for an EMRD ``Door``)."""
    width: float
    """``boundingBox.x``, then ``y`` and ``z``."""
    height: float
    depth: float


@cache
def assets() -> Mapping[str, Asset]:
    """Every vendored asset, by id."""
    text = resources.files(__package__).joinpath("assets.json").read_text(encoding="utf-8")
    data = json.loads(text)["assets"]
    return {
        asset_id: Asset(asset_id, object_type, *box)
        for object_type, rows in data.items()
        for asset_id, box in rows.items()
    }


@cache
def candidates(object_type: str) -> tuple[Asset, ...]:
    """The vendored assets an EMRD object of ``object_type`` can be built from, by id."""
    wanted = ASSET_TYPES.get(object_type, object_type)
    found = tuple(
        sorted((a for a in assets().values() if a.object_type == wanted), key=lambda a: a.asset_id)
    )
    if not found:
        raise ConfigError(
            f"object_type={object_type!r} has no ProcTHOR asset in the vendored table "
            "(pytest_emrd/world/thor/assets.json); use one of the office's object types."
        )
    return found


def asset_by_id(asset_id: str, object_type: str) -> Asset:
    """The vendored asset ``asset_id`` for an object of ``object_type``, or ConfigError."""
    options = candidates(object_type)
    for asset in options:
        if asset.asset_id == asset_id:
            return asset
    raise ConfigError(
        f"asset_ids={{{object_type!r}: {asset_id!r}}} names no {object_type} in the ProcTHOR "
        "asset database (THOR would skip it silently and the object would be missing); use "
        f"one of: {', '.join(a.asset_id for a in options)}."
    )


def _misfit(asset: Asset, width: float, depth: float, height: float) -> float:
    """Metres by which ``asset`` misses the wanted box; oversize counts double."""
    pairs = ((asset.width, width), (asset.depth, depth), (asset.height, height))
    return sum(2.0 * (have - want) if have > want else want - have for have, want in pairs)


def choose_asset(
    object_type: str,
    width: float,
    depth: float,
    height: float,
    overrides: Mapping[str, str] | None = None,
) -> Asset:
    """The asset for a layout object of this type and box (``overrides`` win per type);
    ties go to the smaller asset id."""
    if overrides and object_type in overrides:
        return asset_by_id(overrides[object_type], object_type)
    return min(
        candidates(object_type),
        key=lambda a: (round(_misfit(a, width, depth, height), 6), a.asset_id),
    )
