"""EMRD layout -> ProcTHOR house dict (schema 1.0.0). Pure and deterministic.

The house ``Controller(scene=house)`` accepts: ``rooms``; ``walls``, one per straight
boundary piece per room (a room side is cut at every corner of another room lying on it, so
each piece has one neighbour, a room or the outside) plus one-sided exterior faces;
``doors`` cut as ``holePolygon`` into a wall both rooms own; ``objects``; lights and skybox;
and ``metadata``: the agent's start in ``agentPoses`` (``agent`` repeats it) and our
``emrd`` block (room names, the THOR-id -> EMRD-id table). Why objects stand at
``y = support top + asset height / 2`` (:func:`place`), why the start is a grid point
(:func:`spawn_point`) and what the conditions change: ``docs/ai2thor.md``.
"""

from __future__ import annotations

import itertools
import math
from collections.abc import Mapping, Sequence
from dataclasses import dataclass
from typing import Any, Final

import numpy as np

from pytest_emrd.errors import ConfigError, check_choice
from pytest_emrd.trajectory import CONDITIONS
from pytest_emrd.world._catalog import DOOR_HEIGHT
from pytest_emrd.world._catalog import WALL_HEIGHT as CEILING_HEIGHT
from pytest_emrd.world._conditions import condition_params
from pytest_emrd.world._geometry import Point, Rect, Span, footprint, rect_at
from pytest_emrd.world._model import Doorway, Layout, Room, WorldObject, WorldPose
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
    Asset,
    asset_by_id,
    choose_asset,
)

EPS = 1e-6
"""Tolerance in metres for "on the same line" and "same corner"."""


@dataclass(frozen=True)
class WallPiece:
    """One straight wall piece of one room, in the room's winding order."""

    room: int
    """1-based index of the owning room (``room|<n>`` in the house)."""
    x0: float
    z0: float
    x1: float
    z1: float
    neighbour: int | None
    """Index of the room on the other side, or None for the outside."""

    @property
    def position_id(self) -> str:
        """ProcTHOR's order-free wall key ``minx|minz|maxx|maxz`` (2 decimals)."""
        return (
            f"{min(self.x0, self.x1):.2f}|{min(self.z0, self.z1):.2f}|"
            f"{max(self.x0, self.x1):.2f}|{max(self.z0, self.z1):.2f}"
        )

    @property
    def wall_id(self) -> str:
        return f"wall|{self.room}|{self.position_id}"

    @property
    def length(self) -> float:
        return math.hypot(self.x1 - self.x0, self.z1 - self.z0)

    @property
    def axis(self) -> str:
        """``"x"`` if the piece runs along x, ``"z"`` if along z."""
        return "x" if abs(self.z1 - self.z0) < EPS else "z"

    def offset_of(self, x: float, z: float) -> float | None:
        """Distance along the piece from its start to ``(x, z)``, or None if off the piece."""
        i = 0 if self.axis == "x" else 1  # the coordinate the piece runs along
        start, end, point = (self.x0, self.z0), (self.x1, self.z1), (x, z)
        if abs(point[1 - i] - start[1 - i]) > EPS:
            return None
        along = point[i] - start[i] if end[i] >= start[i] else start[i] - point[i]
        return along if -EPS <= along <= self.length + EPS else None

    def distance_to(self, x: float, z: float) -> float:
        """Euclidean distance from ``(x, z)`` to the piece."""
        dx = max(min(self.x0, self.x1) - x, x - max(self.x0, self.x1), 0.0)
        dz = max(min(self.z0, self.z1) - z, z - max(self.z0, self.z1), 0.0)
        return math.hypot(dx, dz)  # the piece is axis-aligned


def corners(room: Room) -> tuple[Point, ...]:
    """The floor polygon in ProcTHOR's winding: from the south-west corner, north first."""
    return ((room.x0, room.z0), (room.x0, room.z1), (room.x1, room.z1), (room.x1, room.z0))


def _span(room: Room, axis: int) -> Span:
    """The room's extent along x (``axis`` 0) or z (``axis`` 1)."""
    return (room.x0, room.x1) if axis == 0 else (room.z0, room.z1)


def wall_pieces(layout: Layout) -> tuple[WallPiece, ...]:
    """Every wall piece of every room, rooms numbered from 1 in layout order: a side is cut
    where another room's side on the same line ends; a piece's neighbour is the room whose
    side holds the piece's midpoint."""
    pieces: list[WallPiece] = []
    for n, room in enumerate(layout.rooms, start=1):
        poly = corners(room)
        for a, b in zip(poly, poly[1:] + poly[:1], strict=True):
            i = 0 if abs(b[1] - a[1]) < EPS else 1  # the coordinate the side runs along
            on_line = {  # the other rooms with a side on this line -> where that side runs
                m: _span(other, i)
                for m, other in enumerate(layout.rooms, start=1)
                if other is not room and any(abs(c - a[1 - i]) < EPS for c in _span(other, 1 - i))
            }
            lo, hi = sorted((a[i], b[i]))
            cuts = {end for span in on_line.values() for end in span if lo + EPS < end < hi - EPS}
            stops = [a[i], *sorted(cuts, reverse=b[i] < a[i]), b[i]]
            for s, e in itertools.pairwise(stops):
                mid = (s + e) / 2
                covering = (
                    m for m, (s_lo, s_hi) in on_line.items() if s_lo + EPS < mid < s_hi - EPS
                )
                start, end = ((s, a[1]), (e, a[1])) if i == 0 else ((a[0], s), (a[0], e))
                pieces.append(WallPiece(n, *start, *end, next(covering, None)))
    return tuple(pieces)


GRID: Final = 0.25
"""THOR's ``gridSize`` (the backend's default)."""
CLEARANCE: Final = 0.3
"""Metres a spawn point keeps from every asset footprint and wall: THOR's default agent
capsule radius (0.2 m) plus slack for the capsule cast's skin."""
SUPPORT_TOLERANCE: Final = 0.02
"""How far (m) an item's elevation may differ from its support's EMRD height."""


@dataclass(frozen=True)
class Placed:
    """One layout object as THOR builds it."""

    asset: Asset
    x: float
    y: float
    """Centre of the asset's bounding box: support top + asset height / 2."""
    z: float
    rotation: float
    rect: Rect
    """World-axis footprint of the asset at ``(x, z)``."""


def _shift(lo: float, hi: float, room_lo: float, room_hi: float) -> float:
    """The least move of ``[lo, hi]`` into ``[room_lo, room_hi]`` (centred when too long)."""
    if hi - lo > room_hi - room_lo:
        return (room_lo + room_hi) / 2 - (lo + hi) / 2
    return room_lo - lo if lo < room_lo else min(room_hi - hi, 0.0)


def _support(obj: WorldObject, floor: list[WorldObject]) -> WorldObject | None:
    """The floor object ``obj`` stands on: same room, its footprint holds ``obj``'s centre
    and its EMRD top is ``obj``'s elevation."""
    for other in floor:
        x0, z0, x1, z1 = footprint(other)
        if (
            other.room == obj.room
            and abs(other.height - obj.elevation) <= SUPPORT_TOLERANCE
            and x0 <= obj.x <= x1
            and z0 <= obj.z <= z1
        ):
            return other
    return None


def place(layout: Layout, overrides: Mapping[str, str] | None = None) -> dict[str, Placed]:
    """EMRD object id -> its THOR placement, for every object that is not a wall hole."""
    margin = layout.wall_thickness / 2
    solid = [o for o in layout.objects if o.object_type not in DOOR_TYPES]
    floor = [o for o in solid if o.elevation == 0]
    placed: dict[str, Placed] = {}
    for obj in sorted(solid, key=lambda o: o.elevation > 0):
        asset = choose_asset(obj.object_type, obj.width, obj.depth, obj.height, overrides)
        base, dx, dz = obj.elevation, 0.0, 0.0
        if obj.elevation > 0:
            support = _support(obj, floor)
            if support is not None:  # moved with its support
                below = placed[support.object_id]
                base, dx, dz = below.asset.height, below.x - support.x, below.z - support.z
        x, z = obj.x + dx, obj.z + dz
        x0, z0, x1, z1 = rect_at(x, z, asset.width, asset.depth, obj.rotation)
        room = layout.room(obj.room)
        x += _shift(x0, x1, room.x0 + margin, room.x1 - margin)
        z += _shift(z0, z1, room.z0 + margin, room.z1 - margin)
        rect = rect_at(x, z, asset.width, asset.depth, obj.rotation)
        placed[obj.object_id] = Placed(
            asset, x, base + asset.height / 2, z, obj.rotation % 360, rect
        )
    return placed


def snap(value: float) -> float:
    """``value`` on THOR's grid (nearest multiple of :data:`GRID`)."""
    return round(round(value / GRID) * GRID, 4)


def spawn_point(room: Room, footprints: list[Rect], x: float, z: float) -> Point | None:
    """The grid point in ``room`` nearest ``(x, z)`` at least :data:`CLEARANCE` from the
    room's walls and every footprint (None if the room has none)."""
    lo_x = math.ceil((room.x0 + CLEARANCE) / GRID) * GRID
    lo_z = math.ceil((room.z0 + CLEARANCE) / GRID) * GRID
    xs = np.arange(lo_x, room.x1 - CLEARANCE + 1e-9, GRID)
    zs = np.arange(lo_z, room.z1 - CLEARANCE + 1e-9, GRID)
    gx, gz = (a.ravel() for a in np.meshgrid(xs, zs))
    free = np.ones(gx.shape, dtype=bool)
    for x0, z0, x1, z1 in footprints:
        dx = np.maximum(np.maximum(x0 - gx, gx - x1), 0.0)
        dz = np.maximum(np.maximum(z0 - gz, gz - z1), 0.0)
        free &= np.hypot(dx, dz) >= CLEARANCE
    gx, gz = gx[free], gz[free]
    if gx.size == 0:
        return None
    best = np.lexsort((gz, gx, np.round(np.hypot(gx - x, gz - z), 6)))[0]  # nearest, then by x, z
    return snap(float(gx[best])), snap(float(gz[best]))


@dataclass(frozen=True)
class IdTable:
    """Map THOR objectId -> EMRD object id (one to one), read from the table
    :func:`build_house` writes to ``house["metadata"]["emrd"]["ids"]``. THOR objects the
    layout never placed (walls, floors, children spawned by the build) have no EMRD id."""

    to_emrd: Mapping[str, str]

    def __post_init__(self) -> None:
        if len(set(self.to_emrd.values())) != len(self.to_emrd):
            raise ConfigError("the THOR id table maps two THOR objects to one EMRD id.")

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


AGENT_Y = 0.9009997
"""Agent body height THOR reports for the default agent (TeleportFull keeps it)."""


def _xyz(x: float, y: float, z: float) -> dict[str, float]:
    return {"x": round(float(x), 4), "y": round(float(y), 4), "z": round(float(z), 4)}


def _rgb(rgb: Sequence[float]) -> dict[str, float]:
    r, g, b = (round(float(c), 4) for c in rgb)
    return {"r": r, "g": g, "b": b, "a": 1.0}


def _random_color(rng: StableRng) -> list[float]:
    return [rng.uniform(0.05, 0.95) for _ in range(3)]


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
    shared = [p for p in pieces if p.room == a and p.neighbour == b]
    wall0 = next((p for p in shared if p.offset_of(doorway.x, doorway.z) is not None), None)
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
    shadow = {
        "type": "Soft",
        "strength": 1,
        "normalBias": 0,
        "bias": 0.05,
        "nearPlane": 0.2,
        "resolution": "FromQualitySettings",
    }
    return [
        {
            "id": "DirectionalLight",
            "type": "directional",
            "position": _xyz(0.84, 0.1855, -1.09),
            "rotation": _xyz(43.375, -3.902, -63.618),
            "intensity": round(0.35 * factor, 4),
            "indirectMultiplier": 1.0,
            "rgb": _rgb((1.0, 1.0, 1.0)),
            "shadow": shadow,
        },
        *(
            {
                "id": f"light_{n}",
                "type": "point",
                "position": _xyz(r.centre[0], CEILING_HEIGHT - 0.2, r.centre[1]),
                "intensity": round(0.75 * factor, 4),
                "range": 15,
                "rgb": _rgb((1.0, 0.855, 0.722)),
                "shadow": shadow,
            }
            for n, r in enumerate(layout.rooms, start=1)
        ),
    ]


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
    """The agent's start on THOR's grid, clear of every asset (:func:`spawn_point`)."""
    wanted = agent or WorldPose(*layout.rooms[0].centre, 0.0)
    name = layout.room_at(wanted.x, wanted.z)
    footprints = [p.rect for p in placed.values()]
    spot = None if name is None else spawn_point(layout.room(name), footprints, wanted.x, wanted.z)
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
    """The ProcTHOR house for ``layout`` under ``condition``; ``seed`` drives the ``texture``
    colours, ``agent`` is the start (default: centre of the first room, facing north) and
    ``asset_ids`` picks vendored assets per ``objectType`` (``{"Desk": "Desk_204_1"}``)."""
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
    for n, room in enumerate(layout.rooms, start=1):
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
        if obj.object_type in DOOR_TYPES:  # the exit: a hole in an outside wall
            built = _exterior_door(obj, n, len(doors), pieces, assets)
            doors.append(built)
        else:
            built = _object_dict(placed[obj.object_id], f"{obj.object_type}|{n}|{per_room[n]}")
            per_room[n] += 1
            objects.append(built)
        ids[built["id"]] = obj.object_id

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
