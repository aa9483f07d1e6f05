"""Fixtures for the ai2thor backend: hand-built layouts and a fake THOR controller.

:class:`FakeController` honours the ai2thor 5.0.0 contract the backend relies on:
``Controller(**init)`` builds the scene from ``scene=<house dict>``; ``step(action=...,
**args)`` returns an event whose ``metadata`` has ``objects[].objectId/objectType/
position/visible/distance``, ``agent.position/rotation``, ``lastActionSuccess``,
``errorMessage`` and ``actionReturn``, and whose ``frame`` is ``H x W x 3`` uint8;
``reset(scene=..., **init)``, ``stop()``. Unknown actions raise ``ValueError`` as
ai2thor does for ``InvalidAction``. Visibility: inside the 90 degree field of view,
within ``visibilityDistance`` and not behind a wall (doors are holes). Every call is
recorded in ``calls`` as ``(action, args)``.

``thor_installed`` makes the real ai2thor 5.0.0 start-up path (import, pre-flight, build
lookup, ``ai2thor.controller.Controller``) succeed on this machine with the fake in place
of the Controller class: HOME is a fresh tmp dir holding an empty cached build, the Vulkan
loader is reported present, and ``Controller`` is the fake.
"""

from __future__ import annotations

import ctypes.util
import math
import os
import time
from collections.abc import Callable
from dataclasses import dataclass
from pathlib import Path
from typing import Any, ClassVar

import ai2thor.build
import ai2thor.controller
import ai2thor.platform
import numpy as np
import pytest

from pytest_emrd.errors import ConfigError
from pytest_emrd.rooms import CONFERENCE, ENTRANCE, KITCHEN, OFFICE
from pytest_emrd.world._model import Doorway, Layout, Room, WorldObject

GRID = 0.25


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


@dataclass
class FakeEvent:
    metadata: dict[str, Any]
    frame: np.ndarray


def _segments_cross(p: tuple[float, float], q: tuple[float, float], a: Any, b: Any) -> bool:
    def orient(u: Any, v: Any, w: Any) -> float:
        return (v[0] - u[0]) * (w[1] - u[1]) - (v[1] - u[1]) * (w[0] - u[0])

    d1, d2 = orient(a, b, p), orient(a, b, q)
    d3, d4 = orient(p, q, a), orient(p, q, b)
    return d1 * d2 < 0 and d3 * d4 < 0


class FakeController:
    """A THOR stand-in driven by the same house dict a real build would load."""

    instances: ClassVar[list[FakeController]] = []

    def __init__(self, **init: Any) -> None:
        self.init = dict(init)
        self.calls: list[tuple[str, dict[str, Any]]] = []
        self.stopped = False
        self.width, self.height = int(init.get("width", 300)), int(init.get("height", 300))
        FakeController.instances.append(self)
        self._load(init["scene"])

    # -- ai2thor API -------------------------------------------------------------------
    def reset(self, scene: Any = None, **init: Any) -> FakeEvent:
        self.calls.append(("reset", dict(init)))
        self.init.update(init)
        self._load(scene if scene is not None else self.house)
        return self.last_event

    def step(self, action: Any = None, **args: Any) -> FakeEvent:
        if isinstance(action, dict):
            args = {**action, **args}
            action = args.pop("action")
        self.calls.append((str(action), dict(args)))
        handler = getattr(self, f"_do_{action}", None)
        if handler is None:
            raise ValueError(f"Invalid action: {action}")
        ok, message, ret = handler(**args)
        self.last_event = self._event(ok, message, ret, str(action))
        return self.last_event

    def stop(self) -> None:
        self.stopped = True
        self.calls.append(("stop", {}))

    # -- scene -------------------------------------------------------------------------
    def _load(self, house: dict[str, Any]) -> None:
        self.house = house
        self.rooms = [
            (r["id"], [(p["x"], p["z"]) for p in r["floorPolygon"]]) for r in house["rooms"]
        ]
        self.objects = [
            {"objectId": o["id"], "objectType": o["id"].split("|")[0], **o["position"]}
            for o in house["objects"]
        ]
        walls = {w["id"]: w for w in house["walls"]}
        self.doors = []
        for d in house["doors"]:
            w = walls[d["wall0"]]["polygon"]
            (x0, z0), (x1, z1) = (w[0]["x"], w[0]["z"]), (w[1]["x"], w[1]["z"])
            length = math.hypot(x1 - x0, z1 - z0)
            lo, hi = d["holePolygon"][0]["x"] / length, d["holePolygon"][1]["x"] / length
            mid = (lo + hi) / 2
            centre = (x0 + mid * (x1 - x0), z0 + mid * (z1 - z0))
            hole = (_lerp((x0, z0), (x1, z1), lo), _lerp((x0, z0), (x1, z1), hi))
            self.doors.append((d, centre, hole))
            self.objects.append(
                {
                    "objectId": d["id"],
                    "objectType": "Doorway",
                    "x": centre[0],
                    "y": 1.0,
                    "z": centre[1],
                }
            )
        self.walls = self._solid_walls(house)
        agent = house["metadata"]["agent"]
        self.pose = [agent["position"]["x"], agent["position"]["z"], agent["rotation"]["y"] % 360]
        self.reachable = self._grid()
        self.last_event = self._event(True, "", None, "Initialize")

    def _solid_walls(self, house: dict[str, Any]) -> list[tuple[Point, Point]]:
        """Interior wall pieces with door holes cut out, as 2-D segments."""
        solid: list[tuple[Point, Point]] = []
        for w in house["walls"]:
            if w["id"].startswith("wall|exterior"):
                continue
            a = (w["polygon"][0]["x"], w["polygon"][0]["z"])
            b = (w["polygon"][1]["x"], w["polygon"][1]["z"])
            pieces = [(a, b)]
            for d, _, (h0, h1) in self.doors:
                if w["id"] in (d["wall0"], d["wall1"]):
                    pieces = [part for p, q in pieces for part in _cut(p, q, h0, h1)]
            solid += pieces
        return solid

    def _grid(self) -> list[tuple[float, float]]:
        points = []
        for _, poly in self.rooms:
            xs, zs = [p[0] for p in poly], [p[1] for p in poly]
            for x in np.arange(
                math.ceil((min(xs) + 0.2) / GRID) * GRID, max(xs) - 0.2 + 1e-9, GRID
            ):
                for z in np.arange(
                    math.ceil((min(zs) + 0.2) / GRID) * GRID, max(zs) - 0.2 + 1e-9, GRID
                ):
                    blocked = any(
                        math.hypot(o["x"] - x, o["z"] - z) < 0.35
                        for o in self.objects
                        if not o["objectId"].startswith("door|")
                    )
                    if not blocked:
                        points.append((round(float(x), 2), round(float(z), 2)))
        return sorted(set(points))

    # -- actions -----------------------------------------------------------------------
    def _do_GetReachablePositions(self, **_: Any) -> tuple[bool, str, Any]:
        return True, "", [{"x": x, "y": 0.9009997, "z": z} for x, z in self.reachable]

    def _do_TeleportFull(
        self, position: dict[str, float], rotation: dict[str, float], **_: Any
    ) -> tuple[bool, str, Any]:
        key = (round(position["x"], 2), round(position["z"], 2))
        if key not in self.reachable:
            return False, f"position {key} is not reachable", None
        if rotation["y"] % 90:
            return False, "rotation must be a multiple of rotateStepDegrees", None
        self.pose = [position["x"], position["z"], rotation["y"] % 360]
        return True, "", None

    def _do_RotateLeft(self, degrees: float = 90, **_: Any) -> tuple[bool, str, Any]:
        self.pose[2] = (self.pose[2] - degrees) % 360
        return True, "", None

    def _do_RotateRight(self, degrees: float = 90, **_: Any) -> tuple[bool, str, Any]:
        self.pose[2] = (self.pose[2] + degrees) % 360
        return True, "", None

    def _do_RandomizeMaterials(self, **_: Any) -> tuple[bool, str, Any]:
        return True, "", None

    def _do_RandomizeColors(self, **_: Any) -> tuple[bool, str, Any]:
        return True, "", None

    # -- observation -------------------------------------------------------------------
    def _visible(self, o: dict[str, Any]) -> tuple[bool, float]:
        x, z, heading = self.pose
        dist = math.hypot(o["x"] - x, o["z"] - z)
        rel = (math.degrees(math.atan2(o["x"] - x, o["z"] - z)) - heading + 180) % 360 - 180
        in_view = abs(rel) <= 45 and dist <= float(self.init.get("visibilityDistance", 1.5))
        occluded = any(_segments_cross((x, z), (o["x"], o["z"]), a, b) for a, b in self.walls)
        return in_view and not occluded, dist

    def _event(self, ok: bool, message: str, ret: Any, action: str) -> FakeEvent:
        objects = []
        for o in self.objects:
            visible, dist = self._visible(o)
            objects.append(
                {
                    "objectId": o["objectId"],
                    "objectType": o["objectType"],
                    "position": {"x": o["x"], "y": o["y"], "z": o["z"]},
                    "visible": visible,
                    "distance": dist,
                }
            )
        x, z, heading = self.pose
        shade = int(heading // 90) * 40 + int(x * 10) % 40
        frame = np.full((self.height, self.width, 3), shade, dtype=np.uint8)
        frame[: self.height // 2, :, 2] = int(z * 20) % 256
        return FakeEvent(
            metadata={
                "lastAction": action,
                "lastActionSuccess": ok,
                "errorMessage": message,
                "actionReturn": ret,
                "agent": {
                    "position": {"x": x, "y": 0.9009997, "z": z},
                    "rotation": {"x": 0.0, "y": heading, "z": 0.0},
                },
                "objects": objects,
            },
            frame=frame,
        )


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
