"""``ThorSimulator``: the :class:`~pytest_emrd.world._model.Simulator` protocol on AI2-THOR.

One ``Controller`` per simulator, started on the first ``reset``, then re-used with
``controller.reset(scene=<house>)``. Actions take the builtin world's grammar and wording.
``Goto`` teleports on THOR's grid of reachable positions (:func:`viewpoint`, through a
doorway :func:`entry`); ``Turn`` rotates by 90 degree steps; ``Term`` makes no THOR call.
Timeouts, reset's checks and THOR's refusals: ``docs/ai2thor.md``.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable, Iterable, Mapping, Sequence
from typing import Any

import numpy as np

from pytest_emrd.errors import ConfigError, TransportError
from pytest_emrd.world._conditions import condition_params
from pytest_emrd.world._feedback import (
    Action,
    ActionFailed,
    SemanticStep,
    room_table,
    spawn_room_name,
    turn_degrees,
)
from pytest_emrd.world._geometry import Point
from pytest_emrd.world._model import (
    Doorway,
    Layout,
    Observation,
    Room,
    View,
    VisibleObject,
    WorldPose,
)
from pytest_emrd.world._motion import doorway_target, spawn_pose
from pytest_emrd.world._scene import scene_of
from pytest_emrd.world.thor import _launch
from pytest_emrd.world.thor._house import IdTable, build_house

HALF_FOV = 45.0
"""Half of THOR's ``fieldOfView=90``, degrees."""
CLEARANCE = 0.5
"""Minimum distance (m) from a target's centre, or from a doorway's wall, to stand at."""
MAX_OFF_AXIS = 30.0
"""How far (deg) off the view axis a Goto target may end up; beyond, a farther spot wins."""
OFF_AXIS_COST = 0.02
"""Metres of extra distance one degree off the view axis is worth when ranking spots."""
ROOM_MARGIN = 0.05
"""Reachable positions closer than this (m) to a room's edge count as in no room."""


def wrap180(angle: float | np.ndarray) -> Any:
    """Angle(s) wrapped to ``[-180, 180)``."""
    return (np.asarray(angle) + 180.0) % 360.0 - 180.0


def bearing(agent: WorldPose, x: float, z: float) -> float:
    """Bearing of ``(x, z)`` relative to the agent's view axis, negative to the left."""
    heading = math.degrees(math.atan2(x - agent.x, z - agent.z)) % 360.0  # clockwise from +z
    return float(wrap180(heading - agent.heading))


def grid(positions: Iterable[Mapping[str, float]]) -> np.ndarray:
    """``(N, 2)`` array of ``(x, z)`` from THOR's reachable-position dicts."""
    return np.array([(p["x"], p["z"]) for p in positions], dtype=float).reshape(-1, 2)


def _in_room(points: np.ndarray, room: Room) -> np.ndarray:
    x, z = points[:, 0], points[:, 1]
    m = ROOM_MARGIN
    return (x > room.x0 + m) & (x < room.x1 - m) & (z > room.z0 + m) & (z < room.z1 - m)


def _pick(
    points: np.ndarray, heading: float | np.ndarray, *choices: tuple[np.ndarray, np.ndarray]
) -> WorldPose | None:
    """The point with the lowest score under the first ``(score, mask)`` of ``choices`` any
    point passes, facing ``heading`` (one for all, or per point); ties broken by (x, z) so it
    is stable."""
    for score, mask in choices:
        idx = np.flatnonzero(mask)
        if idx.size:
            best = idx[np.lexsort((points[idx, 1], points[idx, 0], np.round(score[idx], 6)))[0]]
            facing = np.broadcast_to(heading, len(points))[best]
            return WorldPose(float(points[best, 0]), float(points[best, 1]), float(facing))
    return None


def nearest_in_room(points: np.ndarray, x: float, z: float, room: Room) -> Point | None:
    """The reachable position in ``room`` nearest ``(x, z)`` (None if the room has none)."""
    dist = np.hypot(points[:, 0] - x, points[:, 1] - z)
    best = _pick(points, 0.0, (dist, _in_room(points, room)))
    return None if best is None else (best.x, best.z)


def viewpoint(points: np.ndarray, x: float, z: float, room: Room) -> WorldPose | None:
    """Reachable spot in ``room`` nearest ``(x, z)`` with a grid heading that faces it.

    Among spots at least :data:`CLEARANCE` away that leave the target within
    :data:`MAX_OFF_AXIS` of the view axis, ranks by distance plus :data:`OFF_AXIS_COST` per
    degree off axis; else the nearest spot in the room; None if the room has none.
    """
    dx, dz = x - points[:, 0], z - points[:, 1]
    dist = np.hypot(dx, dz)
    heading = np.degrees(np.arctan2(dx, dz)) % 360.0
    snapped = (np.round(heading / 90.0) * 90.0) % 360.0
    off_axis = np.abs(wrap180(heading - snapped))
    inside = _in_room(points, room)
    facing = inside & (dist >= CLEARANCE) & (off_axis <= MAX_OFF_AXIS)
    return _pick(points, snapped, (dist + OFF_AXIS_COST * off_axis, facing), (dist, inside))


def entry(points: np.ndarray, doorway: Doorway, into: Room) -> WorldPose | None:
    """Reachable spot in ``into`` nearest the doorway, facing into the room, away from the gap."""
    x, z = points[:, 0], points[:, 1]
    if doorway.axis == "x":  # wall runs along x at z = doorway.z
        north = abs(into.z0 - doorway.z) < abs(into.z1 - doorway.z)
        heading, depth = (0.0, z - doorway.z) if north else (180.0, doorway.z - z)
    else:  # wall runs along z at x = doorway.x
        east = abs(into.x0 - doorway.x) < abs(into.x1 - doorway.x)
        heading, depth = (90.0, x - doorway.x) if east else (270.0, doorway.x - x)
    dist = np.hypot(x - doorway.x, z - doorway.z)
    inside = _in_room(points, into)
    return _pick(points, heading, (dist, inside & (depth >= CLEARANCE)), (dist, inside))


def agent_pose(metadata: Mapping[str, Any]) -> WorldPose:
    """The agent's pose from an event's metadata."""
    agent = metadata["agent"]
    return WorldPose(
        float(agent["position"]["x"]),
        float(agent["position"]["z"]),
        float(agent["rotation"]["y"]) % 360.0,
    )


def visible_objects(
    objects: Sequence[Mapping[str, Any]],
    agent: WorldPose,
    *,
    ids: IdTable,
    types: Mapping[str, str],
    landmarks: frozenset[str],
    visibility_distance: float,
) -> tuple[VisibleObject, ...]:
    """EMRD objects THOR reports ``visible``, sorted by id: ``landmarks`` (EMRD ids) as THOR
    says, every other object only within ``visibility_distance`` of its bounding box
    (``docs/ai2thor.md``); ``types`` maps EMRD id -> EMRD type."""
    seen: dict[str, VisibleObject] = {}
    for obj in objects:
        ours = ids.emrd(str(obj["objectId"])) if obj.get("visible") else None
        if ours is None:  # not visible, or not an object of the layout
            continue
        x, z = float(obj["position"]["x"]), float(obj["position"]["z"])
        if ours not in landmarks and _box_distance(obj, agent) > visibility_distance:
            continue
        b = min(HALF_FOV, max(-HALF_FOV, bearing(agent, x, z)))
        distance = round(math.hypot(x - agent.x, z - agent.z), 2)
        seen[ours] = VisibleObject(ours, types[ours], round(b, 1), distance)
    return tuple(seen[k] for k in sorted(seen))


def _box_distance(obj: Mapping[str, Any], agent: WorldPose) -> float:
    """Horizontal distance from the agent to the nearest point of ``obj``'s bounding box."""
    box = obj["axisAlignedBoundingBox"]
    cx, cz = float(box["center"]["x"]), float(box["center"]["z"])
    hx, hz = float(box["size"]["x"]) / 2, float(box["size"]["z"]) / 2
    dx = max(abs(agent.x - cx) - hx, 0.0)
    dz = max(abs(agent.z - cz) - hz, 0.0)
    return math.hypot(dx, dz)


JPEG_QUALITY = 90
DEFAULTS: Mapping[str, Any] = {
    "agentMode": "default",
    "width": 512,
    "height": 512,
    "fieldOfView": 90,
    "snapToGrid": True,
    "gridSize": 0.25,
    "rotateStepDegrees": 90,
}


def _positive(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or value <= 0:
        raise ConfigError(f"{name}={value!r} must be a number of seconds > 0.")
    return float(value)


def _check(event: Any, what: str) -> Any:
    metadata = event.metadata
    if metadata["lastActionSuccess"]:
        return event
    message = " ".join(str(metadata.get("errorMessage") or "no errorMessage").split())
    raise ConfigError(
        f"AI2-THOR refused {what}: {message} (see ~/.ai2thor/log/unity.log for the Unity side)."
    )


def _accepted(event: Any) -> None:
    if not event.metadata["lastActionSuccess"]:
        reason = event.metadata.get("errorMessage") or "no reason"
        raise ActionFailed(f"AI2-THOR refused it ({reason})")


class ThorSimulator(SemanticStep):
    """The ai2thor backend. Construction is cheap; THOR starts on the first ``reset``.

    ``controller_options`` go to ``Controller(...)`` over :data:`DEFAULTS` (for example
    ``local_executable_path``, ``gpu_device``, ``platform``). ``controller_factory``
    replaces ``ai2thor.controller.Controller`` (tests pass a fake). ``allow_download``
    lets ai2thor fetch a missing build (under ``start_timeout``). ``room_aliases`` are extra
    names ``Term`` accepts. ``frame_digest`` is the SHA-256 of the pixels THOR returned on
    this machine (not bit-stable across GPUs, drivers and builds).
    """

    def __init__(
        self,
        *,
        controller_factory: Callable[..., Any] | None = None,
        start_timeout: float = 180.0,
        step_timeout: float = 60.0,
        allow_download: bool = False,
        asset_ids: Mapping[str, str] | None = None,
        room_aliases: Mapping[str, str] | None = None,
        **controller_options: Any,
    ) -> None:
        self._factory = controller_factory
        self._start_timeout = _positive("start_timeout", start_timeout)
        self._step_timeout = _positive("step_timeout", step_timeout)
        self._allow_download = bool(allow_download)
        self._asset_ids = dict(asset_ids or {})
        self._rooms = room_table(room_aliases)
        self._options = {**DEFAULTS, **controller_options}
        self._controller: Any = None
        self._started: list[Any] = []
        self._layout: Layout | None = None
        self._house: dict[str, Any] = {}
        self._ids = IdTable({})
        self._condition = condition_params("baseline")
        self._points = np.empty((0, 2))
        self._heights: dict[Point, float] = {}
        self._spawn = WorldPose(0.0, 0.0, 0.0)
        self._visible: tuple[VisibleObject, ...] = ()

    def _start(self, house: dict[str, Any]) -> None:
        options = {
            **self._options,
            "scene": house,
            "visibilityDistance": self._condition.draw_distance,
            "server_timeout": self._step_timeout,
            "server_start_timeout": self._start_timeout,
        }
        self._started = []
        if self._factory is None:
            thor = _launch.import_ai2thor()
            options.setdefault("platform", thor.platform.CloudRendering)
            options = _launch.headless_options(options)
            _launch.preflight(thor, options, allow_download=self._allow_download)
            factory: Callable[..., Any] = _launch.launcher(
                thor.controller.Controller, self._started
            )
        else:
            options.setdefault("platform", "CloudRendering")
            factory = self._factory
        self._controller = _launch.start(
            factory, options, seconds=self._start_timeout, started=self._started
        )

    def _call(self, what: str, fn: Callable[[], Any]) -> Any:
        def on_timeout() -> TransportError:
            controller, self._controller, self._layout = self._controller, None, None
            _launch.kill_unity(controller)
            return TransportError(
                f"AI2-THOR did not answer {what} within step_timeout={self._step_timeout:g} s; "
                "the Unity process hangs or died (see ~/.ai2thor/log/unity.log)."
            )

        try:
            return _launch.bounded(fn, seconds=self._step_timeout, on_timeout=on_timeout)
        except TransportError:
            raise
        except Exception as exc:
            raise TransportError(f"AI2-THOR failed on {what}: {type(exc).__name__}: {exc}") from exc

    def _act(self, action: str, **args: Any) -> Any:
        return self._call(action, lambda: self._controller.step(action=action, **args))

    def _teleport(self, pose: WorldPose) -> Any:
        """``TeleportFull`` to a lattice point, at the height THOR returned for it."""
        y = self._heights[(round(pose.x, 2), round(pose.z, 2))]
        return self._act(
            "TeleportFull",
            position={"x": pose.x, "y": y, "z": pose.z},
            rotation={"x": 0.0, "y": pose.heading, "z": 0.0},
            horizon=0,
            standing=True,
        )

    def _lattice(self) -> None:
        """THOR's reachable positions from the agent's start, with their heights."""
        event = _check(self._act("GetReachablePositions"), "GetReachablePositions")
        returned = event.metadata["actionReturn"] or []
        self._points = grid(returned)
        self._heights = {(round(p["x"], 2), round(p["z"], 2)): float(p["y"]) for p in returned}

    def reset(
        self, layout: Layout, condition: str, spawn_room: str, seed: int, *, symbolic: bool = True
    ) -> Observation:
        """Start an episode in ``spawn_room`` (canonical name or slug) under ``condition``."""
        name = spawn_room_name(spawn_room)
        self._condition = condition_params(condition)
        room = layout.room(name)
        wanted = spawn_pose(scene_of(layout), room, seed)
        mode = str(self._options["agentMode"])
        house = build_house(
            layout, condition, seed, agent=wanted, asset_ids=self._asset_ids, agent_mode=mode
        )
        if self._controller is None:
            self._start(house)
        else:
            vis = self._condition.draw_distance
            self._call("reset", lambda: self._controller.reset(scene=house, visibilityDistance=vis))
        self._layout, self._house, self._ids = layout, house, IdTable.from_house(house)
        _check(self._controller.last_event, f"CreateHouse of house {house['id']!r}")
        self._lattice()
        if self._condition.randomize_palette:
            every = {"useTrainMaterials": True, "useValMaterials": True, "useTestMaterials": True}
            _check(self._act("RandomizeMaterials", **every), "RandomizeMaterials")
            _check(self._act("RandomizeColors"), "RandomizeColors")
        start = house["metadata"]["agentPoses"][mode]["position"]
        spot = nearest_in_room(self._points, start["x"], start["z"], room)
        if spot is None:
            raise ConfigError(
                f"AI2-THOR reports no reachable position in spawn_room={spawn_room!r} from the "
                f"start x={start['x']}, z={start['z']} of house {house['id']!r}; check that "
                "the build loaded the house (see ~/.ai2thor/log/unity.log)."
            )
        event = _check(
            self._teleport(WorldPose(spot[0], spot[1], wanted.heading)), "the spawn TeleportFull"
        )
        self._spawn = agent_pose(event.metadata)
        return self._begin(symbolic)

    @property
    def agent_pose(self) -> WorldPose:
        self._require()
        return agent_pose(self._controller.last_event.metadata)

    @property
    def house(self) -> Mapping[str, Any]:
        """The ProcTHOR house of the current episode."""
        return self._house

    def current_room(self) -> str:
        layout = self._require()
        pose = self.agent_pose
        room = layout.room_at(pose.x, pose.z)
        if room is None:
            raise TransportError(f"AI2-THOR put the agent outside every room at {pose}.")
        return room

    def close(self) -> None:
        controller, self._controller, self._layout = self._controller, None, None
        if controller is not None:
            try:
                self._call("stop", controller.stop)
            finally:
                _launch.kill_unity(controller)

    def _in_view(self) -> tuple[VisibleObject, ...]:
        return self._visible

    def _reach(self, object_id: str) -> bool:
        layout = self._require()
        doorway = next((d for d in layout.doorways if d.object_id == object_id), None)
        if doorway is None:
            obj = next(o for o in layout.objects if o.object_id == object_id)
            pose = viewpoint(self._points, obj.x, obj.z, layout.room(obj.room))
        else:
            target, passing = doorway_target(layout, doorway, self.agent_pose, self.current_room())
            if passing:  # through the doorway
                pose = entry(self._points, doorway, target)
            else:  # up to it from a third room
                pose = viewpoint(self._points, doorway.x, doorway.z, target)
        if pose is not None:
            _accepted(self._teleport(pose))
        return pose is not None

    def _turn(self, action: Action) -> str:
        degrees = turn_degrees(action)  # -90, 90 or 180: RotateLeft, or 90-degree RotateRights
        for _ in range(int(abs(degrees)) // 90):
            _accepted(self._act("RotateLeft" if degrees < 0 else "RotateRight", degrees=90))
        return ""

    def _require(self) -> Layout:
        if self._layout is None:
            raise ConfigError("ThorSimulator used before reset(); call reset(layout, ...) first.")
        return self._layout

    def _view(self) -> tuple[WorldPose, tuple[VisibleObject, ...], str, View]:
        event = self._controller.last_event
        world = agent_pose(event.metadata)
        objects = self._require().objects
        self._visible = visible_objects(
            event.metadata["objects"],
            world,
            ids=self._ids,
            types={o.object_id: o.object_type for o in objects},
            landmarks=frozenset(o.object_id for o in objects if o.category == "landmark"),
            visibility_distance=self._condition.visibility_distance,
        )
        frame = np.ascontiguousarray(event.frame, dtype=np.uint8)
        if frame.ndim != 3 or frame.shape[2] != 3:
            raise TransportError(f"AI2-THOR returned a frame of shape {frame.shape}, not HxWx3.")
        digest = hashlib.sha256(frame.tobytes()).hexdigest()
        return world, self._visible, digest, View.of(frame, JPEG_QUALITY)
