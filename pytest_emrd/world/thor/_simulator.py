"""``ThorSimulator``: the :class:`~pytest_emrd.world._model.Simulator` protocol on AI2-THOR.

One ``Controller`` per simulator, started on the first ``reset`` with ``scene=<house>`` and
:data:`DEFAULTS`, then re-used with ``controller.reset(scene=<house>)``. Actions are read
and answered with the builtin world's grammar and wording (:mod:`pytest_emrd.world._feedback`).
``Goto`` teleports (``TeleportFull``) to :func:`~._navigation.viewpoint`, through a doorway
to :func:`~._navigation.entry`; ``Turn`` rotates by 90 degree steps; ``Term`` makes no THOR
call. The spawn is the builtin world's, moved to the nearest free point of THOR's grid.
Reset checks each THOR answer it depends on; a refusal is one :class:`ConfigError` line
carrying THOR's ``errorMessage`` (``docs/ai2thor.md``). Every THOR call is bounded
(``start_timeout``, ``step_timeout``); on a timeout the Unity process group is killed and
the next reset starts a new controller.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np

from pytest_emrd.errors import ConfigError, TransportError, check_choice
from pytest_emrd.rooms import ROOM_NAMES, SLUG_ROOMS
from pytest_emrd.world._conditions import condition_params
from pytest_emrd.world._feedback import (
    Action,
    ActionFailed,
    SemanticStep,
    choose_target,
    goto_key,
    goto_note,
    no_spot,
    not_visible,
    observed_pose,
    room_table,
    turn_degrees,
    with_pose,
)
from pytest_emrd.world._model import Doorway, Layout, Observation, View, VisibleObject, WorldPose
from pytest_emrd.world._motion import spawn_pose
from pytest_emrd.world._scene import scene_of
from pytest_emrd.world.thor import _launch
from pytest_emrd.world.thor._house import IdTable, build_house
from pytest_emrd.world.thor._navigation import (
    agent_pose,
    entry,
    grid,
    nearest_in_room,
    viewpoint,
    visible_objects,
)

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
ROTATIONS: Mapping[float, tuple[str, ...]] = {
    -90.0: ("RotateLeft",),
    90.0: ("RotateRight",),
    180.0: ("RotateRight", "RotateRight"),
}
"""Clockwise degrees of a ``Turn`` -> the THOR rotations (90 degrees each)."""


def _positive(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or value <= 0:
        raise ConfigError(f"{name}={value!r} must be a number of seconds > 0.")
    return float(value)


def _check(event: Any, what: str) -> Any:
    """``event`` if THOR reports success, else ConfigError with THOR's own message."""
    metadata = event.metadata
    if metadata["lastActionSuccess"]:
        return event
    message = " ".join(str(metadata.get("errorMessage") or "no errorMessage").split())
    raise ConfigError(
        f"AI2-THOR refused {what}: {message} (see ~/.ai2thor/log/unity.log for the Unity side)."
    )


def _accepted(event: Any) -> None:
    """Raise the failure to report when THOR refused an action."""
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
        self._user_options = dict(controller_options)
        self._controller: Any = None
        self._started: list[Any] = []
        self._layout: Layout | None = None
        self._house: dict[str, Any] = {}
        self._ids = IdTable({})
        self._types: dict[str, str] = {}
        self._landmarks: frozenset[str] = frozenset()
        self._condition = condition_params("baseline")
        self._points = np.empty((0, 2))
        self._heights: dict[tuple[float, float], float] = {}
        self._spawn = WorldPose(0.0, 0.0, 0.0)
        self._visible: tuple[VisibleObject, ...] = ()
        self._steps = 0
        self._ended = False
        self._terminal: str | None = None
        self._symbolic = True

    def _start(self, house: dict[str, Any]) -> None:
        options = {**DEFAULTS, **self._user_options}
        options.update(
            scene=house,
            visibilityDistance=self._condition.draw_distance,
            server_timeout=self._step_timeout,
            server_start_timeout=self._start_timeout,
        )
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
        name = SLUG_ROOMS.get(spawn_room, spawn_room)
        check_choice("spawn_room", name, [*ROOM_NAMES, *SLUG_ROOMS])
        self._condition = condition_params(condition)
        room = layout.room(name)
        wanted = spawn_pose(scene_of(layout), room, seed)
        mode = str({**DEFAULTS, **self._user_options}["agentMode"])
        house = build_house(
            layout, condition, seed, agent=wanted, asset_ids=self._asset_ids, agent_mode=mode
        )
        if self._controller is None:
            self._start(house)
        else:
            vis = self._condition.draw_distance
            self._call("reset", lambda: self._controller.reset(scene=house, visibilityDistance=vis))
        self._layout, self._house, self._ids = layout, house, IdTable.from_house(house)
        self._types = {o.object_id: o.object_type for o in layout.objects}
        self._landmarks = frozenset(o.object_id for o in layout.objects if o.category == "landmark")
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
        self._steps, self._ended, self._terminal, self._symbolic = 0, False, None, symbolic
        return self._observe(True, "Episode started.")

    @property
    def agent_pose(self) -> WorldPose:
        self._require()
        return agent_pose(self._controller.last_event.metadata)

    @property
    def spawn_pose(self) -> WorldPose:
        self._require()
        return self._spawn

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

    def visible_ids(self) -> tuple[str, ...]:
        self._require()
        return tuple(v.object_id for v in self._visible)

    def close(self) -> None:
        controller, self._controller = self._controller, None
        self._layout = None
        if controller is not None:
            try:
                self._call("stop", controller.stop)
            finally:
                _launch.kill_unity(controller)

    def _goto(self, action: Action) -> str:
        layout = self._require()
        symbolic = self._symbolic
        key = goto_key(action, symbolic=symbolic)
        seen = self._visible
        chosen = choose_target(
            key,
            [v.object_id for v in seen],
            [v.object_type for v in seen],
            [v.distance for v in seen],
            symbolic=symbolic,
        )
        if chosen is None:
            raise not_visible(action, [v.object_id for v in seen], symbolic=symbolic)
        target = seen[chosen].object_id
        doorway = next((d for d in layout.doorways if d.object_id == target), None)
        if doorway is None:
            obj = next(o for o in layout.objects if o.object_id == target)
            pose = viewpoint(self._points, obj.x, obj.z, layout.room(obj.room))
        else:
            pose = self._door_pose(layout, doorway)
        if pose is None:
            raise no_spot(target, seen[chosen].object_type, symbolic=symbolic)
        _accepted(self._teleport(pose))
        return goto_note(key, target, symbolic=symbolic)

    def _turn(self, action: Action) -> str:
        for rotate in ROTATIONS[turn_degrees(action)]:
            _accepted(self._act(rotate, degrees=90))
        return ""

    def _door_pose(self, layout: Layout, doorway: Doorway) -> WorldPose | None:
        """Through the doorway from one of its rooms; up to it from a third room."""
        here = self.current_room()
        a, b = layout.room(doorway.room_a), layout.room(doorway.room_b)
        if here in (a.name, b.name):
            return entry(self._points, doorway, b if here == a.name else a)
        pose = self.agent_pose
        if doorway.axis == "x":  # rooms lie north and south of the wall at z = doorway.z
            near_a = (pose.z >= doorway.z) == ((a.z0 + a.z1) / 2 >= doorway.z)
        else:
            near_a = (pose.x >= doorway.x) == ((a.x0 + a.x1) / 2 >= doorway.x)
        return viewpoint(self._points, doorway.x, doorway.z, a if near_a else b)

    def _require(self) -> Layout:
        if self._layout is None:
            raise ConfigError("ThorSimulator used before reset(); call reset(layout, ...) first.")
        return self._layout

    def _observe(self, success: bool, message: str) -> Observation:
        event = self._controller.last_event
        world = agent_pose(event.metadata)
        self._visible = visible_objects(
            event.metadata["objects"],
            world,
            ids=self._ids,
            types=self._types,
            landmarks=self._landmarks,
            visibility_distance=self._condition.visibility_distance,
        )
        frame = np.ascontiguousarray(event.frame, dtype=np.uint8)
        if frame.ndim != 3 or frame.shape[2] != 3:
            raise TransportError(f"AI2-THOR returned a frame of shape {frame.shape}, not HxWx3.")
        pose = observed_pose(self._spawn, world)
        return Observation(
            step=self._steps,
            pose=pose,
            success=success,
            feedback=with_pose(message, pose),
            visible=self._visible,
            frame_digest=hashlib.sha256(frame.tobytes()).hexdigest(),
            view=View.of(frame, JPEG_QUALITY),
            done=self._ended,
            terminal_room=self._terminal,
        )
