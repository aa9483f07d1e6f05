"""Fixtures for the ai2thor backend: hand-built layouts and a contract-true fake THOR.

:class:`FakeController` enforces the ai2thor 5.0.0 contract the backend relies on, as the
sources define it (Python side: the installed ``ai2thor`` package; Unity side:
allenai/ai2thor ``unity/Assets/Scripts``; houses: allenai/procthor 1.0.0):

* ``Controller(scene=<house>, **init)`` sends ``Initialize`` and then ``CreateHouse``
  (``ai2thor/controller.py`` lines 731-738); ``reset(scene=...)`` reloads the empty
  procedural scene first (lines 659-663), so the agent is back at :data:`EMPTY_START`,
  below where any house stands.
* ``step`` answers like ``Controller.step`` (lines 933-1011): an action outside
  :data:`ACTIONS` fails with ``errorCode`` ``InvalidAction``, an argument the C# method
  does not take with ``InvalidArgument``, a required argument left out with
  ``MissingArguments`` (``ActionDispatcher.cs``, ``Dispatch``: ``InvalidArgumentsException``
  and ``MissingArgumentsActionException``), and those three raise ``ValueError`` on the
  Python side (``controller.py`` lines 1002-1009). Other failures are events with
  ``lastActionSuccess=False`` and THOR's ``errorMessage``.
* ``CreateHouse`` spawns each object from the asset database vendored in
  ``data/asset_database.json`` (1,653 ids with their bounding boxes), centring the asset's
  box on ``position`` (``ProceduralTools.cs``, ``spawnHouseObject``:
  ``positionBoundingBoxCenter: true``); an unknown ``assetId`` is skipped silently and the
  action still succeeds ("Asset not in Database" goes to the Unity log only). It moves the
  agent only to ``metadata.agentPoses[agentMode]`` (``ProceduralTools.cs``,
  ``setAgentPose``); ``metadata.agent`` is ignored.
* ``GetReachablePositions`` walks the grid (``gridSize``) outward from where the agent
  stands, over floor clear of walls and asset boxes by the agent's capsule radius
  (:data:`AGENT_RADIUS`); from a start off the floor it fails, as allenai/procthor#4
  reports. Every position carries the agent's standing height.
* ``TeleportFull(position, rotation, horizon, standing, forceAction=False)``
  (``PhysicsRemoteFPSAgentController.cs``) refuses, in ``teleportFull``'s order
  (``BaseFPSAgentController.cs``; the wording as in ``FpinAgentController.teleportFull``,
  which repeats those checks): pitch or roll, a horizon outside [-30, 60], a position
  out of the scene bounds, a position off the grid (``isPositionOnGrid``: ``x`` and ``z``
  multiples of ``gridSize``), a colliding capsule, and a ``y`` more than 0.05 m from where
  the agent stands on the floor (``assertTeleportedNearGround``).
* Events are real ``ai2thor.server.Event`` objects whose metadata has THOR's key set
  (:data:`EVENT_KEYS`, :data:`AGENT_KEYS`, :data:`OBJECT_KEYS`) and an ``H x W x 3``
  uint8 ``frame``. ``visible`` is THOR's flag: an object's visibility point (box corner or
  centre, a door's hole ends or centre) in the 90 degree view, unoccluded by a wall, within
  ``visibilityDistance`` measured horizontally.

Every call is recorded in ``calls`` as ``(action, args)``; ``reset`` as ``("reset", init)``.

``thor_installed`` makes the real ai2thor 5.0.0 start-up path (import, pre-flight, build
lookup, ``ai2thor.controller.Controller``) succeed on this machine with the fake in place
of the Controller class: HOME is a fresh tmp dir holding an empty cached build, the Vulkan
loader is reported present, and ``Controller`` is the fake.
"""

from __future__ import annotations

import copy
import ctypes.util
import json
import math
import os
import time
from collections import deque
from collections.abc import Callable
from pathlib import Path
from typing import Any, ClassVar

import ai2thor.build
import ai2thor.controller
import ai2thor.platform
import ai2thor.server
import numpy as np
import pytest

from pytest_emrd.errors import ConfigError
from pytest_emrd.rooms import CONFERENCE, ENTRANCE, KITCHEN, OFFICE
from pytest_emrd.world import Doorway, Layout, Room, WorldObject

ASSET_DB: dict[str, list[Any]] = json.loads(
    (Path(__file__).parent / "data" / "asset_database.json").read_text(encoding="utf-8")
)["assets"]
"""assetId -> [objectType, boundingBox.x, boundingBox.y, boundingBox.z] (see data/README.md)."""

EMPTY_START = {"x": -0.5, "y": -38.9, "z": 0.5}
"""Where the agent stands in the empty procedural scene before any house is applied."""
AGENT_Y = 0.9009997
"""The default agent's standing height above the floor (what THOR reports as ``y``)."""
AGENT_RADIUS = 0.2
"""The default agent's capsule radius (m)."""
CAMERA_ABOVE_AGENT = 0.675
MAX_UP, MAX_DOWN = 30.0, 60.0
"""``maxUpwardLookAngle`` / ``maxDownwardLookAngle`` of the default agent."""

#: action -> (required arguments, optional arguments), from the C# method signatures:
#: ``TeleportFull`` and ``RotateLeft``/``RotateRight`` in ``PhysicsRemoteFPSAgentController``,
#: ``GetReachablePositions`` in ``BaseFPSAgentController``, ``CreateHouse`` and the
#: randomisers in ai2thor's procedural actions. ``Initialize`` takes a ``ServerAction``
#: (any key), listed as ``None``.
ACTIONS: dict[str, tuple[frozenset[str], frozenset[str]] | None] = {
    "Initialize": None,
    "CreateHouse": (frozenset({"house"}), frozenset()),
    "GetReachablePositions": (
        frozenset(),
        frozenset({"maxStepCount", "directionsRelativeAgent", "gridSize"}),
    ),
    "TeleportFull": (
        frozenset({"position", "rotation", "horizon", "standing"}),
        frozenset({"forceAction"}),
    ),
    "RotateLeft": (frozenset(), frozenset({"degrees", "manualInteract", "forceAction"})),
    "RotateRight": (frozenset(), frozenset({"degrees", "manualInteract", "forceAction"})),
    "RandomizeMaterials": (
        frozenset(),
        frozenset(
            {
                "useTrainMaterials",
                "useValMaterials",
                "useTestMaterials",
                "useExternalMaterials",
                "inRoomTypes",
            }
        ),
    ),
    "RandomizeColors": (frozenset(), frozenset()),
}

EVENT_KEYS = frozenset(
    {
        "objects", "agent", "sceneName", "lastAction", "lastActionSuccess", "errorMessage",
        "errorCode", "actionReturn", "screenWidth", "screenHeight", "fov", "cameraPosition",
        "isSceneAtRest", "collided", "collidedObjects", "inventoryObjects", "sceneBounds",
        "thirdPartyCameras", "colors", "agentId", "currentTime",
    }
)  # fmt: skip
AGENT_KEYS = frozenset(
    {"name", "position", "rotation", "cameraHorizon", "isStanding", "inHighFrictionArea"}
)
OBJECT_KEYS = frozenset(
    {
        "objectId", "objectType", "name", "assetId", "position", "rotation", "visible",
        "isInteractable", "distance", "axisAlignedBoundingBox", "receptacle", "moveable",
        "pickupable", "parentReceptacles",
    }
)  # fmt: skip

Point = tuple[float, float]


def _lerp(p: Point, q: Point, t: float) -> Point:
    return (p[0] + t * (q[0] - p[0]), p[1] + t * (q[1] - p[1]))


def _param(p: Point, q: Point, h: Point) -> float:
    return ((h[0] - p[0]) * (q[0] - p[0]) + (h[1] - p[1]) * (q[1] - p[1])) / (
        (q[0] - p[0]) ** 2 + (q[1] - p[1]) ** 2
    )


def _cut(p: Point, q: Point, h0: Point, h1: Point) -> list[tuple[Point, Point]]:
    """Segment p->q minus the span h0..h1 lying on its line."""
    lo, hi = sorted((_param(p, q, h0), _param(p, q, h1)))
    if hi <= 0 or lo >= 1:
        return [(p, q)]
    return ([(p, _lerp(p, q, lo))] if lo > 0 else []) + ([(_lerp(p, q, hi), q)] if hi < 1 else [])


def _segments_cross(p: Point, q: Point, a: Point, b: Point) -> bool:
    def orient(u: Point, v: Point, w: Point) -> float:
        return (v[0] - u[0]) * (w[1] - u[1]) - (v[1] - u[1]) * (w[0] - u[0])

    d1, d2 = orient(a, b, p), orient(a, b, q)
    d3, d4 = orient(p, q, a), orient(p, q, b)
    return d1 * d2 < 0 and d3 * d4 < 0


def _segment_distance(px: np.ndarray, pz: np.ndarray, a: Point, b: Point) -> np.ndarray:
    dx, dz = b[0] - a[0], b[1] - a[1]
    t = np.clip(((px - a[0]) * dx + (pz - a[1]) * dz) / (dx * dx + dz * dz), 0.0, 1.0)
    return np.hypot(px - (a[0] + t * dx), pz - (a[1] + t * dz))


def _rect_distance(px: np.ndarray, pz: np.ndarray, rect: tuple[float, ...]) -> np.ndarray:
    x0, z0, x1, z1 = rect
    dx = np.maximum(np.maximum(x0 - px, px - x1), 0.0)
    dz = np.maximum(np.maximum(z0 - pz, pz - z1), 0.0)
    return np.hypot(dx, dz)


class FakeController:
    """A THOR stand-in driven by the same house dict a real build would load."""

    instances: ClassVar[list[FakeController]] = []

    def __init__(self, **init: Any) -> None:
        self.init = dict(init)
        self.calls: list[tuple[str, dict[str, Any]]] = []
        self.stopped = False
        self.width, self.height = int(init.get("width", 300)), int(init.get("height", 300))
        self.agent_y = AGENT_Y
        self.reachable: list[Point] = []
        FakeController.instances.append(self)
        self.scene = init.get("scene")
        self._load_empty()
        self.last_event = self.step(action="Initialize", raise_for_failure=True, **self._params())
        if isinstance(self.scene, dict):
            self.last_event = self.step(action="CreateHouse", house=self.scene)

    # -- ai2thor API -------------------------------------------------------------------
    def reset(self, scene: Any = None, **init: Any) -> Any:
        self.calls.append(("reset", dict(init)))
        self.init.update(init)
        self.scene = scene if scene is not None else self.scene
        self._load_empty()
        self.step(action="Initialize", raise_for_failure=True, **self._params())
        self.last_event = self.step(action="CreateHouse", house=self.scene)
        return self.last_event

    def step(self, action: Any = None, **args: Any) -> Any:
        if isinstance(action, dict):
            args = {**copy.deepcopy(action), **args}
            action = args.pop("action")
        raise_for_failure = args.pop("raise_for_failure", False)
        self.calls.append((str(action), dict(args)))
        ok, message, code, ret = self._dispatch(str(action), args)
        self.last_event = self._event(ok, message, code, ret, str(action))
        if not ok:
            if code in ("InvalidAction", "MissingArguments", "AmbiguousAction", "InvalidArgument"):
                raise ValueError(message)
            if raise_for_failure:
                raise RuntimeError(message)
        return self.last_event

    def _params(self) -> dict[str, Any]:
        """The Unity initialisation parameters among the constructor's keyword arguments."""
        python_side = {"scene", "width", "height", "platform", "server_timeout"}
        return {k: v for k, v in self.init.items() if k not in python_side}

    def stop(self) -> None:
        self.stopped = True
        self.calls.append(("stop", {}))

    # -- dispatch (ActionDispatcher.Dispatch) -------------------------------------------
    def _dispatch(self, action: str, args: dict[str, Any]) -> tuple[bool, str, str, Any]:
        if action not in ACTIONS:
            return False, f"Invalid action: {action}", "InvalidAction", None
        rule = ACTIONS[action]
        if rule is not None:
            required, optional = rule
            unexpected = sorted(set(args) - required - optional)
            if unexpected:
                return (
                    False,
                    f"{action} got unexpected arguments: {', '.join(unexpected)}",
                    "InvalidArgument",
                    None,
                )
            missing = sorted(required - set(args))
            if missing:
                return (
                    False,
                    f"{action} is missing arguments: {', '.join(missing)}",
                    "MissingArguments",
                    None,
                )
        ok, message, ret = getattr(self, f"_do_{action}")(**args)
        return ok, message, "", ret

    # -- scene -------------------------------------------------------------------------
    def _load_empty(self) -> None:
        """The empty ``Procedural`` scene: no house, the agent below where one will stand."""
        self.rooms: list[tuple[str, tuple[float, float, float, float]]] = []
        self.walls: list[tuple[Point, Point]] = []
        self.objects: list[dict[str, Any]] = []
        self.doors: list[tuple[dict[str, Any], Point, tuple[Point, Point]]] = []
        self.pose = {**EMPTY_START, "heading": 0.0, "horizon": 0.0, "standing": True}

    def _do_Initialize(self, **params: Any) -> tuple[bool, str, Any]:
        self.grid_size = float(params.get("gridSize", self.init.get("gridSize", 0.25)))
        self.rotate_step = float(params.get("rotateStepDegrees", 90))
        self.visibility = float(params.get("visibilityDistance", 1.5))
        self.agent_mode = str(params.get("agentMode", "default"))
        return True, "", None

    def _do_CreateHouse(self, house: dict[str, Any]) -> tuple[bool, str, Any]:
        for key in ("rooms", "walls", "doors", "objects", "proceduralParameters"):
            if key not in house:
                return False, f"house has no '{key}'", None
        for r in house["rooms"]:
            xs, zs = [p["x"] for p in r["floorPolygon"]], [p["z"] for p in r["floorPolygon"]]
            self.rooms.append((r["id"], (min(xs), min(zs), max(xs), max(zs))))
        for o in house["objects"]:
            if o["assetId"] not in ASSET_DB:
                continue  # "Asset not in Database": logged by Unity, skipped, not an error
            object_type, bx, by, bz = ASSET_DB[o["assetId"]]
            turned = round(o["rotation"]["y"]) % 180 == 90
            hx, hz = (bz, bx) if turned else (bx, bz)
            x, y, z = o["position"]["x"], o["position"]["y"], o["position"]["z"]
            self.objects.append(
                {
                    "objectId": o["id"],
                    "objectType": object_type,
                    "assetId": o["assetId"],
                    "x": x,
                    "y": y,
                    "z": z,
                    "rotation": o["rotation"]["y"],
                    "box": (bx, by, bz),
                    "rect": (x - hx / 2, z - hz / 2, x + hx / 2, z + hz / 2),
                    "bottom": y - by / 2,
                }
            )
        walls = {w["id"]: w for w in house["walls"]}
        for d in house["doors"]:
            if d["wall0"] not in walls or d["wall1"] not in walls:
                return False, f"door {d['id']} names a wall the house does not have", None
            w = walls[d["wall0"]]["polygon"]
            (x0, z0), (x1, z1) = (w[0]["x"], w[0]["z"]), (w[1]["x"], w[1]["z"])
            length = math.hypot(x1 - x0, z1 - z0)
            lo, hi = d["holePolygon"][0]["x"] / length, d["holePolygon"][1]["x"] / length
            centre = _lerp((x0, z0), (x1, z1), (lo + hi) / 2)
            hole = (_lerp((x0, z0), (x1, z1), lo), _lerp((x0, z0), (x1, z1), hi))
            self.doors.append((d, centre, hole))
        self.walls = self._solid_walls(house)
        pose = (house.get("metadata") or {}).get("agentPoses", {}).get(self.agent_mode)
        if pose is not None:
            self.pose = {
                **pose["position"],
                "heading": pose["rotation"]["y"] % 360,
                "horizon": pose.get("horizon", 0.0),
                "standing": pose.get("standing", True),
            }
        return True, "", None

    def _solid_walls(self, house: dict[str, Any]) -> list[tuple[Point, Point]]:
        """Room wall pieces with door holes cut out, as 2-D segments."""
        solid: list[tuple[Point, Point]] = []
        for w in house["walls"]:
            if w["id"].startswith("wall|exterior"):
                continue  # the outside face of a room wall already listed
            a = (w["polygon"][0]["x"], w["polygon"][0]["z"])
            b = (w["polygon"][1]["x"], w["polygon"][1]["z"])
            pieces = [(a, b)]
            for d, _, (h0, h1) in self.doors:
                if w["id"] in (d["wall0"], d["wall1"]):
                    pieces = [part for p, q in pieces for part in _cut(p, q, h0, h1)]
            solid += pieces
        return solid

    # -- geometry ----------------------------------------------------------------------
    def _free(self, px: np.ndarray, pz: np.ndarray) -> np.ndarray:
        """Where the agent's capsule fits: on a room's floor, clear of walls and assets."""
        on_floor = np.zeros(px.shape, dtype=bool)
        for _, (x0, z0, x1, z1) in self.rooms:
            on_floor |= (px >= x0) & (px <= x1) & (pz >= z0) & (pz <= z1)
        free = on_floor
        for a, b in self.walls:
            free &= _segment_distance(px, pz, a, b) >= AGENT_RADIUS
        for o in self.objects:
            if o["bottom"] < 1.8:  # anything lower than the agent blocks it
                free &= _rect_distance(px, pz, o["rect"]) >= AGENT_RADIUS
        return free

    def _in_bounds(self, x: float, z: float) -> bool:
        return any(x0 <= x <= x1 and z0 <= z <= z1 for _, (x0, z0, x1, z1) in self.rooms)

    # -- actions -----------------------------------------------------------------------
    def _do_GetReachablePositions(
        self,
        maxStepCount: int | None = None,
        directionsRelativeAgent: bool = False,
        gridSize: float | None = None,
    ) -> tuple[bool, str, Any]:
        g = float(gridSize or self.grid_size)
        ax, az = self.pose["x"], self.pose["z"]
        start_free = bool(self._free(np.array([ax]), np.array([az]))[0])
        if abs(self.pose["y"] - self.agent_y) > 1.0 or not start_free:
            return (
                False,
                f"({ax:.2f}, {self.pose['y']:.2f}, {az:.2f}) can be reached via capsule cast "
                "but is beyond the scene bounds.",
                None,
            )
        x0, z0, x1, z1 = (
            min(r[0] for _, r in self.rooms),
            min(r[1] for _, r in self.rooms),
            max(r[2] for _, r in self.rooms),
            max(r[3] for _, r in self.rooms),
        )
        i = np.arange(math.floor((x0 - ax) / g), math.ceil((x1 - ax) / g) + 1)
        j = np.arange(math.floor((z0 - az) / g), math.ceil((z1 - az) / g) + 1)
        gi, gj = np.meshgrid(i, j, indexing="ij")
        free = self._free(ax + gi * g, az + gj * g)
        origin = (int(-i[0]), int(-j[0]))
        seen, queue, order = {origin}, deque([origin]), []
        while queue:
            a, b = queue.popleft()
            order.append((a, b))
            for da, db in ((1, 0), (0, -1), (-1, 0), (0, 1)):
                n = (a + da, b + db)
                if n in seen or not (0 <= n[0] < len(i) and 0 <= n[1] < len(j)):
                    continue
                if free[n]:
                    seen.add(n)
                    queue.append(n)
        self.reachable = [
            (round(ax + float(i[a]) * g, 4), round(az + float(j[b]) * g, 4)) for a, b in order
        ]
        return True, "", [{"x": x, "y": self.agent_y, "z": z} for x, z in self.reachable]

    def _do_TeleportFull(
        self,
        position: dict[str, float],
        rotation: dict[str, float],
        horizon: float,
        standing: bool,
        forceAction: bool = False,
    ) -> tuple[bool, str, Any]:
        x, y, z = float(position["x"]), float(position["y"]), float(position["z"])
        if abs(rotation.get("x", 0.0)) > 1e-6 or abs(rotation.get("z", 0.0)) > 1e-6:
            return (
                False,
                "No agents currently can change in pitch or roll. So, you must set "
                f"rotation(x=0, y=yaw, z=0). You gave {rotation}.",
                None,
            )
        if not forceAction and not -MAX_UP <= horizon <= MAX_DOWN:
            return False, f"Each horizon must be in [-30:60]. You gave {horizon}.", None
        if not forceAction and not self._in_bounds(x, z):
            return False, f"Teleport position ({x}, {y}, {z}) out of scene bounds!", None
        g = self.grid_size
        on_grid = all(abs(round(v / g) * g - v) < 1e-4 for v in (x, z))
        if not forceAction and not on_grid:
            return (
                False,
                f"Teleport position ({x:.6f}, {y:.6f}, {z:.6f}) is not on the grid of size {g}.",
                None,
            )
        if not forceAction and not self._free(np.array([x]), np.array([z]))[0]:
            return False, "Cannot teleport: the agent's capsule collides at the target.", None
        if not forceAction and abs(y - self.agent_y) > 0.05:
            return (
                False,
                "After teleporting and adjusting agent position to floor, there was too large a "
                f"change ({abs(y - self.agent_y):.3f} > 0.05) in the y component.",
                None,
            )
        self.pose = {
            "x": x,
            "y": self.agent_y,
            "z": z,
            "heading": float(rotation.get("y", 0.0)) % 360,
            "horizon": float(horizon),
            "standing": bool(standing),
        }
        return True, "", None

    def _rotate(self, degrees: float | None) -> tuple[bool, str, Any]:
        step = self.rotate_step if degrees is None else float(degrees)
        self.pose["heading"] = (self.pose["heading"] + step) % 360
        return True, "", None

    def _do_RotateLeft(
        self, degrees: float | None = None, manualInteract: bool = False, forceAction: bool = False
    ) -> tuple[bool, str, Any]:
        return self._rotate(-(self.rotate_step if degrees is None else float(degrees)))

    def _do_RotateRight(
        self, degrees: float | None = None, manualInteract: bool = False, forceAction: bool = False
    ) -> tuple[bool, str, Any]:
        return self._rotate(degrees)

    def _do_RandomizeMaterials(self, **flags: Any) -> tuple[bool, str, Any]:
        return True, "", None

    def _do_RandomizeColors(self) -> tuple[bool, str, Any]:
        return True, "", None

    # -- observation -------------------------------------------------------------------
    def _points(self, o: dict[str, Any]) -> list[Point]:
        if "rect" not in o:
            return [(o["x"], o["z"]), *o["hole"]]
        x0, z0, x1, z1 = o["rect"]
        return [(o["x"], o["z"]), (x0, z0), (x0, z1), (x1, z0), (x1, z1)]

    def _visible(self, o: dict[str, Any]) -> bool:
        ax, az, heading = self.pose["x"], self.pose["z"], self.pose["heading"]
        for px, pz in self._points(o):
            if math.hypot(px - ax, pz - az) > self.visibility:
                continue
            rel = (math.degrees(math.atan2(px - ax, pz - az)) - heading + 180) % 360 - 180
            if abs(rel) > 45:
                continue
            if not any(_segments_cross((ax, az), (px, pz), a, b) for a, b in self.walls):
                return True
        return False

    def _object_meta(self, o: dict[str, Any]) -> dict[str, Any]:
        ax, az = self.pose["x"], self.pose["z"]
        cy = self.pose["y"] + CAMERA_ABOVE_AGENT
        bx, by, bz = o.get("box", (1.0, 2.1, 0.1))
        return {
            "objectId": o["objectId"],
            "objectType": o["objectType"],
            "name": o["objectId"],
            "assetId": o.get("assetId", ""),
            "position": {"x": o["x"], "y": o["y"], "z": o["z"]},
            "rotation": {"x": 0.0, "y": o.get("rotation", 0.0), "z": 0.0},
            "visible": self._visible(o),
            "isInteractable": False,
            "distance": math.dist((ax, cy, az), (o["x"], o["y"], o["z"])),
            "axisAlignedBoundingBox": {
                "center": {"x": o["x"], "y": o["y"], "z": o["z"]},
                "size": {"x": bx, "y": by, "z": bz},
            },
            "receptacle": False,
            "moveable": False,
            "pickupable": False,
            "parentReceptacles": None,
        }

    def _event(self, ok: bool, message: str, code: str, ret: Any, action: str) -> Any:
        doors = [
            {
                "objectId": d["id"],
                "objectType": "Doorway",
                "assetId": d["assetId"],
                "x": centre[0],
                "y": 1.0,
                "z": centre[1],
                "hole": hole,
            }
            for d, centre, hole in self.doors
        ]
        x, z, heading = self.pose["x"], self.pose["z"], self.pose["heading"]
        metadata = {
            "objects": [self._object_meta(o) for o in [*self.objects, *doors]],
            "agent": {
                "name": "agent",
                "position": {"x": x, "y": self.pose["y"], "z": z},
                "rotation": {"x": 0.0, "y": heading, "z": 0.0},
                "cameraHorizon": self.pose["horizon"],
                "isStanding": self.pose["standing"],
                "inHighFrictionArea": False,
            },
            "sceneName": "Procedural",
            "lastAction": action,
            "lastActionSuccess": ok,
            "errorMessage": message,
            "errorCode": code,
            "actionReturn": ret,
            "screenWidth": self.width,
            "screenHeight": self.height,
            "fov": float(self.init.get("fieldOfView", 90)),
            "cameraPosition": {"x": x, "y": self.pose["y"] + CAMERA_ABOVE_AGENT, "z": z},
            "isSceneAtRest": True,
            "collided": False,
            "collidedObjects": [],
            "inventoryObjects": [],
            "sceneBounds": {},
            "thirdPartyCameras": [],
            "colors": [],
            "agentId": 0,
            "currentTime": 0.0,
        }
        event = ai2thor.server.Event(metadata)
        shade = int(heading // 90) * 40 + int(abs(x) * 10) % 40
        frame = np.full((self.height, self.width, 3), shade, dtype=np.uint8)
        frame[: self.height // 2, :, 2] = int(abs(z) * 20) % 256
        event.frame = frame
        return event


def _obj(
    oid: str, room: str, x: float, z: float, category: str = "salient", size: float = 0.6
) -> WorldObject:
    return WorldObject(oid, oid.split("_")[0], room, category, x, z, size, size, 0.8)


def small_layout(*, seed: int = 7) -> Layout:
    """A 2x2 office, rooms of unequal width, three doorways and an exit."""
    rooms = (
        Room(OFFICE, 0.0, 4.0, 4.0, 8.0),
        Room(CONFERENCE, 4.0, 4.0, 9.0, 8.0),
        Room(KITCHEN, 0.0, 0.0, 5.0, 4.0),
        Room(ENTRANCE, 5.0, 0.0, 9.0, 4.0),
    )
    doorways = (
        Doorway("Doorway_1", OFFICE, CONFERENCE, 4.0, 6.0, 1.0, "z"),
        Doorway("Doorway_2", OFFICE, KITCHEN, 2.0, 4.0, 1.0, "x"),
        Doorway("Doorway_3", KITCHEN, ENTRANCE, 5.0, 2.0, 1.0, "z"),
    )
    objects = (
        *(
            WorldObject(d.object_id, "Doorway", d.room_a, "landmark", d.x, d.z, d.width, 0.1, 2.1)
            for d in doorways
        ),
        WorldObject("Door_1", "Door", ENTRANCE, "landmark", 9.0 - 0.05, 2.0, 1.0, 0.1, 2.1),
        _obj("Desk_1", OFFICE, 1.0, 7.0),
        _obj("Chair_1", OFFICE, 1.0, 6.2, "clutter", 0.4),
        _obj("DiningTable_1", CONFERENCE, 6.5, 6.0, size=1.2),
        _obj("Television_1", CONFERENCE, 8.6, 6.0, size=0.3),
        _obj("Fridge_1", KITCHEN, 0.5, 0.5),
        _obj("Sink_1", KITCHEN, 3.0, 0.4, size=0.5),
        _obj("ArmChair_1", ENTRANCE, 7.0, 3.3),
        _obj("HousePlant_1", ENTRANCE, 8.5, 0.5, "clutter", 0.3),
    )
    return Layout(seed=seed, width=9.0, depth=8.0, rooms=rooms, doorways=doorways, objects=objects)


@pytest.fixture
def failed_reset() -> Callable[[Any, Layout, float], Exception]:
    """``failed_reset(sim, layout, limit)``: reset must raise ConfigError within ``limit`` s."""

    def check(sim: Any, layout: Layout, limit: float) -> Exception:
        started = time.monotonic()
        with pytest.raises(ConfigError) as info:
            sim.reset(layout, "baseline", "Office", 0)
        assert time.monotonic() - started < limit
        return info.value

    return check


@pytest.fixture
def layout() -> Layout:
    return small_layout()


@pytest.fixture
def fake_controller() -> type[FakeController]:
    """The fake's class (pass it as ``controller_factory``); instances are recorded."""
    FakeController.instances.clear()
    return FakeController


@pytest.fixture
def isolated_home(tmp_path: Path, monkeypatch: pytest.MonkeyPatch) -> None:
    """No real ~/.ai2thor: no cached build, logs land in tmp_path."""
    monkeypatch.setenv("HOME", str(tmp_path))


@pytest.fixture
def vulkan(monkeypatch: pytest.MonkeyPatch) -> None:
    """Pretend the Vulkan loader is installed (this machine has none)."""
    real = ctypes.util.find_library
    monkeypatch.setattr(
        ctypes.util, "find_library", lambda n: "libvulkan.so.1" if n == "vulkan" else real(n)
    )


@pytest.fixture
def thor_installed(
    isolated_home: None, vulkan: None, monkeypatch: pytest.MonkeyPatch
) -> type[FakeController]:
    """ai2thor's own start-up path with the fake as ``ai2thor.controller.Controller``."""
    from pytest_emrd.world.thor._launch import releases_dir

    platform = ai2thor.platform.CloudRendering
    build = ai2thor.build.Build(platform, ai2thor.build.COMMIT_ID, False, releases_dir())
    os.makedirs(build.base_dir)
    FakeController.instances.clear()
    monkeypatch.setattr(ai2thor.controller, "Controller", FakeController)
    return FakeController


def still_running(pids: list[int], *, within: float = 5.0) -> list[int]:
    """The processes of ``pids`` still alive after waiting up to ``within`` seconds for them to
    exit (a zombie awaiting its reaper counts as exited)."""

    def alive(pid: int) -> bool:
        try:
            with open(f"/proc/{pid}/stat", encoding="ascii") as stat:
                return stat.read().rsplit(")", 1)[1].split()[0] != "Z"
        except FileNotFoundError:
            return False

    deadline = time.monotonic() + within
    while any(alive(p) for p in pids) and time.monotonic() < deadline:
        time.sleep(0.05)
    return [p for p in pids if alive(p)]
