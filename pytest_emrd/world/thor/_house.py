"""EMRD layout -> ProcTHOR house dict (schema 1.0.0). Pure and deterministic.

The house ``Controller(scene=house)`` accepts: ``rooms``, ``walls`` (one per boundary piece
and room, plus one-sided exterior faces), ``doors`` cut as ``holePolygon`` into a wall both
rooms own, ``objects`` with their assets (:mod:`._placement`), lights and skybox, and
``metadata``: the agent's start in ``agentPoses`` (the only pose ``CreateHouse`` applies;
``agent`` repeats it, procthor's convention) and our ``emrd`` block (room names, the
THOR-id -> EMRD-id table). ``low_light`` scales the lights and dims the skybox; ``texture``
gives walls and floors seeded colours. See ``docs/ai2thor.md``.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pytest_emrd.errors import ConfigError, check_choice
from pytest_emrd.trajectory import CONDITIONS
from pytest_emrd.world._catalog import DOOR_HEIGHT
from pytest_emrd.world._catalog import WALL_HEIGHT as CEILING_HEIGHT
from pytest_emrd.world._conditions import condition_params
from pytest_emrd.world._model import Doorway, Layout, WorldObject, WorldPose
from pytest_emrd.world._rng import StableRng
from pytest_emrd.world.thor._assets import (
    CEILING_MATERIAL,
    DIM_SKYBOX_ID,
    DOOR_TYPES,
    FLOOR_MATERIAL,
    SCHEMA,
    SKYBOX_ID,
    THOR_ROOM_TYPES,
    WALL_COLOR,
    asset_by_id,
    choose_asset,
)
from pytest_emrd.world.thor._placement import Placed, place, spawn_point
from pytest_emrd.world.thor._walls import WallPiece, corners, wall_pieces


@dataclass(frozen=True)
class IdTable:
    """Bidirectional map THOR objectId <-> EMRD object id, read from the table
    :func:`build_house` writes to ``house["metadata"]["emrd"]["ids"]``. THOR objects the
    layout never placed (walls, floors, children spawned by the build) have no EMRD id."""

    to_emrd: Mapping[str, str]
    to_thor: Mapping[str, str] = field(init=False, repr=False)

    def __post_init__(self) -> None:
        inverse = {ours: thor for thor, ours in self.to_emrd.items()}
        if len(inverse) != len(self.to_emrd):
            raise ConfigError("the THOR id table maps two THOR objects to one EMRD id.")
        object.__setattr__(self, "to_thor", inverse)

    @classmethod
    def from_house(cls, house: Mapping[str, Any]) -> IdTable:
        """The table of a house :func:`build_house` made (ConfigError for any other)."""
        try:
            table = house["metadata"]["emrd"]["ids"]
        except (KeyError, TypeError):
            raise ConfigError(
                "house has no metadata.emrd.ids table; build it with "
                "pytest_emrd.world.thor.build_house."
            ) from None
        return cls(dict(table))

    def emrd(self, thor_id: str) -> str | None:
        """The EMRD id of a THOR object, or None if the layout never placed it."""
        return self.to_emrd.get(thor_id)

    def thor(self, emrd_id: str) -> str:
        """The THOR objectId of an EMRD object (KeyError if unknown)."""
        return self.to_thor[emrd_id]


AGENT_Y = 0.9009997
"""Agent body height THOR reports for the default agent (TeleportFull keeps it)."""


def _xyz(x: float, y: float, z: float) -> dict[str, float]:
    return {"x": round(float(x), 4), "y": round(float(y), 4), "z": round(float(z), 4)}


def _rgb(rgb: tuple[float, float, float]) -> dict[str, float]:
    r, g, b = (round(float(c), 4) for c in rgb)
    return {"r": r, "g": g, "b": b, "a": 1.0}


def _random_color(rng: StableRng) -> tuple[float, float, float]:
    return (rng.uniform(0.05, 0.95), rng.uniform(0.05, 0.95), rng.uniform(0.05, 0.95))


def _wall_dict(piece: WallPiece, room_id: str, color: dict[str, float]) -> dict[str, Any]:
    return {
        "id": piece.wall_id,
        "roomId": room_id,
        "polygon": [
            _xyz(piece.x0, 0.0, piece.z0),
            _xyz(piece.x1, 0.0, piece.z1),
            _xyz(piece.x0, CEILING_HEIGHT, piece.z0),
            _xyz(piece.x1, CEILING_HEIGHT, piece.z1),
        ],
        "material": {"color": color},
    }


def _exterior_dict(piece: WallPiece, room_id: str) -> dict[str, Any]:
    wall = _wall_dict(piece, room_id, _rgb(WALL_COLOR))
    wall["id"] = f"wall|exterior|{piece.position_id}"
    wall["polygon"] = list(reversed(wall["polygon"]))
    return wall


def _hole(piece: WallPiece, x: float, z: float, width: float, what: str) -> dict[str, Any]:
    """``holePolygon`` + ``assetPosition`` of a ``width`` gap centred at ``(x, z)``."""
    t = piece.offset_of(x, z)
    if t is None or t - width / 2 < -1e-6 or t + width / 2 > piece.length + 1e-6:
        raise ConfigError(
            f"{what} at x={x}, z={z} (width={width}) does not fit on wall {piece.wall_id}; "
            "doorways must lie on a wall both rooms share, clear of its ends."
        )
    lo, hi = max(0.0, t - width / 2), min(piece.length, t + width / 2)
    return {
        "holePolygon": [_xyz(lo, 0.0, 0.0), _xyz(hi, DOOR_HEIGHT, 0.0)],
        "assetPosition": _xyz((lo + hi) / 2, DOOR_HEIGHT / 2, 0.0),
    }


def _interior_door(
    doorway: Doorway,
    numbers: Mapping[str, int],
    pieces: tuple[WallPiece, ...],
    assets: Mapping[str, str],
) -> dict[str, Any]:
    a, b = numbers[doorway.room_a], numbers[doorway.room_b]
    wall0 = next(
        (
            p
            for p in pieces
            if p.room == a and p.neighbour == b and p.offset_of(doorway.x, doorway.z) is not None
        ),
        None,
    )
    if wall0 is None or wall0.axis != doorway.axis:
        raise ConfigError(
            f"doorway {doorway.object_id} at x={doorway.x}, z={doorway.z} (axis={doorway.axis!r})"
            f" is not on a wall shared by {doorway.room_a!r} and {doorway.room_b!r}; "
            "fix the layout so the gap sits on their common wall."
        )
    return {
        "id": f"door|{min(a, b)}|{max(a, b)}",
        "room0": f"room|{a}",
        "room1": f"room|{b}",
        "wall0": wall0.wall_id,
        "wall1": f"wall|{b}|{wall0.position_id}",
        "assetId": choose_asset("Doorway", doorway.width, 0.1, DOOR_HEIGHT, assets).asset_id,
        "openable": True,
        "openness": 1.0,
        **_hole(wall0, doorway.x, doorway.z, doorway.width, doorway.object_id),
    }


def _exterior_door(
    obj: WorldObject, n: int, index: int, pieces: tuple[WallPiece, ...], assets: Mapping[str, str]
) -> dict[str, Any]:
    outside = [p for p in pieces if p.room == n and p.neighbour is None]
    if not outside:
        raise ConfigError(
            f"exit {obj.object_id} is in room {obj.room!r}, which has no outside wall; "
            "place the building exit in a room on the edge of the office."
        )
    wall0 = min(outside, key=lambda p: p.distance_to(obj.x, obj.z))
    # Snap the exit's centre onto the wall line (objects sit just inside the room).
    x, z = (obj.x, wall0.z0) if wall0.axis == "x" else (wall0.x0, obj.z)
    return {
        "id": f"door|exterior|{index}",
        "room0": f"room|{n}",
        "room1": f"room|{n}",
        "wall0": wall0.wall_id,
        "wall1": f"wall|exterior|{wall0.position_id}",
        "assetId": choose_asset(obj.object_type, obj.width, obj.depth, obj.height, assets).asset_id,
        "openable": False,
        "openness": 0.0,
        **_hole(wall0, x, z, obj.width, obj.object_id),
    }


def _lights(layout: Layout, factor: float) -> list[dict[str, Any]]:
    shadow = {"type": "Soft", "strength": 1, "normalBias": 0, "bias": 0.05, "nearPlane": 0.2}
    lights: list[dict[str, Any]] = [
        {
            "id": "DirectionalLight",
            "type": "directional",
            "position": _xyz(0.84, 0.1855, -1.09),
            "rotation": _xyz(43.375, -3.902, -63.618),
            "intensity": round(0.35 * factor, 4),
            "indirectMultiplier": 1.0,
            "rgb": _rgb((1.0, 1.0, 1.0)),
            "shadow": {**shadow, "resolution": "FromQualitySettings"},
        }
    ]
    for n, room in enumerate(layout.rooms, start=1):
        lights.append(
            {
                "id": f"light_{n}",
                "type": "point",
                "position": _xyz(
                    (room.x0 + room.x1) / 2, CEILING_HEIGHT - 0.2, (room.z0 + room.z1) / 2
                ),
                "intensity": round(0.75 * factor, 4),
                "range": 15,
                "rgb": _rgb((1.0, 0.855, 0.722)),
                "shadow": {**shadow, "resolution": "FromQualitySettings"},
            }
        )
    return lights


def _object_dict(placed: Placed, thor_id: str) -> dict[str, Any]:
    return {
        "id": thor_id,
        "assetId": placed.asset.asset_id,
        "position": _xyz(placed.x, placed.y, placed.z),
        "rotation": _xyz(0.0, placed.rotation, 0.0),
        "kinematic": True,
        "layer": "Procedural0",
    }


def _start(layout: Layout, placed: Mapping[str, Placed], agent: WorldPose | None) -> dict[str, Any]:
    """The agent's start on THOR's grid, clear of every asset (see :mod:`._placement`)."""
    first = layout.rooms[0]
    wanted = agent or WorldPose((first.x0 + first.x1) / 2, (first.z0 + first.z1) / 2, 0.0)
    name = layout.room_at(wanted.x, wanted.z)
    spot = None
    if name is not None:
        spot = spawn_point(layout.room(name), [p.rect for p in placed.values()], wanted.x, wanted.z)
    if spot is None:
        raise ConfigError(
            f"agent pose x={wanted.x}, z={wanted.z} has no free THOR grid point in its room "
            f"({name!r}); start the agent inside a room with free floor."
        )
    return {
        "horizon": 0,
        "position": _xyz(spot[0], AGENT_Y, spot[1]),
        "rotation": _xyz(0.0, wanted.heading % 360, 0.0),
        "standing": True,
    }


def build_house(
    layout: Layout,
    condition: str,
    seed: int,
    *,
    agent: WorldPose | None = None,
    asset_ids: Mapping[str, str] | None = None,
    agent_mode: str = "default",
) -> dict[str, Any]:
    """The ProcTHOR house (schema 1.0.0) for ``layout`` under ``condition``.

    ``seed`` drives the ``texture`` colours; ``agent`` is where the agent should start
    (default: centre of the first room, facing north), moved to the nearest free grid point
    of its room and written to ``metadata.agentPoses[agent_mode]``; ``asset_ids`` picks the
    asset per ``objectType`` (``{"Desk": "Desk_204_1"}``) instead of the footprint choice,
    from the vendored asset table only (ConfigError otherwise).
    """
    check_choice("condition", condition, CONDITIONS)
    assets = dict(asset_ids or {})
    for object_type, asset_id in assets.items():
        asset_by_id(asset_id, object_type)
    placed = place(layout, assets)
    numbers = {room.name: n for n, room in enumerate(layout.rooms, start=1)}
    pieces = wall_pieces(layout)
    rng = StableRng(seed)
    textured = condition == "texture"

    rooms, walls = [], []
    for room in layout.rooms:
        n = numbers[room.name]
        floor: dict[str, Any] = {"name": FLOOR_MATERIAL}
        wall_color = _rgb(_random_color(rng) if textured else WALL_COLOR)
        if textured:
            floor["color"] = _rgb(_random_color(rng))
        rooms.append(
            {
                "id": f"room|{n}",
                "roomType": THOR_ROOM_TYPES.get(room.name, "LivingRoom"),
                "floorPolygon": [_xyz(x, 0.0, z) for x, z in corners(room)],
                "floorMaterial": floor,
                "ceilings": [],
                "children": [],
            }
        )
        walls += [_wall_dict(p, f"room|{n}", wall_color) for p in pieces if p.room == n]
    walls += [_exterior_dict(p, f"room|{p.room}") for p in pieces if p.neighbour is None]

    doorway_ids = {d.object_id for d in layout.doorways}
    doors = [_interior_door(d, numbers, pieces, assets) for d in layout.doorways]
    ids = {door["id"]: d.object_id for door, d in zip(doors, layout.doorways, strict=True)}
    objects, per_room = [], dict.fromkeys(numbers.values(), 0)
    for obj in layout.objects:
        if obj.object_id in doorway_ids:
            continue
        n = numbers[obj.room]
        if obj.object_type in DOOR_TYPES:
            door = _exterior_door(obj, n, len(doors), pieces, assets)
            doors.append(door)
            ids[door["id"]] = obj.object_id
            continue
        thor_id = f"{obj.object_type}|{n}|{per_room[n]}"
        per_room[n] += 1
        objects.append(_object_dict(placed[obj.object_id], thor_id))
        ids[thor_id] = obj.object_id

    start = _start(layout, placed, agent)
    return {
        "id": f"emrd-{layout.seed}-{condition}-{seed}",
        "rooms": rooms,
        "walls": walls,
        "doors": doors,
        "windows": [],
        "objects": objects,
        "proceduralParameters": {
            "ceilingMaterial": {"name": CEILING_MATERIAL},
            "floorColliderThickness": 1.0,
            "receptacleHeight": 0.7,
            "reflections": [],
            "skyboxId": DIM_SKYBOX_ID if condition == "low_light" else SKYBOX_ID,
            "lights": _lights(layout, condition_params(condition).light_factor),
        },
        "metadata": {
            "schema": SCHEMA,
            "agentPoses": {agent_mode: start},
            "agent": start,
            "emrd": {
                "layout_seed": layout.seed,
                "condition": condition,
                "seed": seed,
                "rooms": {f"room|{n}": name for name, n in numbers.items()},
                "ids": ids,
            },
        },
    }
