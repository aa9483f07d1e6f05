"""``ThorSimulator``: the :class:`~pytest_emrd.world._model.Simulator` protocol on AI2-THOR.

One ``ai2thor.controller.Controller`` per simulator, started on the first ``reset`` with
``scene=<house>`` (agentMode default, CloudRendering, 512x512, fieldOfView 90,
snapToGrid, rotateStepDegrees 90, the condition's visibilityDistance) and re-used with
``controller.reset(scene=<house>)`` afterwards. Semantic actions map to THOR actions:

* ``Goto(object)``  -> ``TeleportFull`` to :func:`~._navigation.viewpoint`;
* ``Goto(Doorway)`` -> ``TeleportFull`` to :func:`~._navigation.entry` in the other room;
* ``Turn(Left|Right|Around)`` -> ``RotateLeft`` / ``RotateRight`` / ``RotateRight`` twice;
* ``Term(room)`` -> no THOR call; ends the episode.

Every THOR call is bounded by the watchdog (``start_timeout``, ``step_timeout``).
"""

from __future__ import annotations

import hashlib
import io
from collections.abc import Callable, Mapping
from typing import Any

import numpy as np
from PIL import Image

from pytest_emrd.errors import ConfigError, TransportError, check_choice
from pytest_emrd.trajectory import Pose
from pytest_emrd.world._geometry import heading_in_spawn_frame, to_spawn_frame
from pytest_emrd.world._model import Doorway, Layout, Observation, VisibleObject, WorldPose
from pytest_emrd.world._rng import StableRng
from pytest_emrd.world.thor import _grammar, _launch
from pytest_emrd.world.thor._conditions import ThorCondition, thor_condition
from pytest_emrd.world.thor._house import AGENT_Y, build_house
from pytest_emrd.world.thor._ids import IdTable
from pytest_emrd.world.thor._navigation import (
    agent_pose,
    entry,
    grid,
    nearest_in_room,
    viewpoint,
    visible_objects,
)
from pytest_emrd.world.thor._watchdog import bounded

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
ROTATIONS = {"Left": ("RotateLeft",), "Right": ("RotateRight",), "Around": ("RotateRight",) * 2}


def _positive(name: str, value: float) -> float:
    if isinstance(value, bool) or not isinstance(value, int | float) or value <= 0:
        raise ConfigError(f"{name}={value!r} must be a number of seconds > 0.")
    return float(value)


def _jpeg(frame: np.ndarray) -> bytes:
    buffer = io.BytesIO()
    Image.fromarray(frame).save(buffer, format="JPEG", quality=JPEG_QUALITY)
    return buffer.getvalue()


class ThorSimulator:
    """The ai2thor backend. Construction is cheap; THOR starts on the first ``reset``.

    ``controller_options`` go to ``Controller(...)`` over :data:`DEFAULTS` (for example
    ``local_executable_path``, ``gpu_device``, ``platform``); ``scene`` and
    ``visibilityDistance`` come from the layout and condition. ``controller_factory``
    replaces ``ai2thor.controller.Controller`` (tests pass a fake). ``allow_download``
    lets ai2thor fetch a missing build (under ``start_timeout``); by default a missing
    build fails at once.
    """

    def __init__(
        self,
        *,
        controller_factory: Callable[..., Any] | None = None,
        start_timeout: float = 180.0,
        step_timeout: float = 60.0,
        allow_download: bool = False,
        asset_ids: Mapping[str, str] | None = None,
        **controller_options: Any,
    ) -> None:
        self._factory = controller_factory
        self._start_timeout = _positive("start_timeout", start_timeout)
        self._step_timeout = _positive("step_timeout", step_timeout)
        self._allow_download = bool(allow_download)
        self._asset_ids = dict(asset_ids or {})
        self._user_options = dict(controller_options)
        self._controller: Any = None
        self._layout: Layout | None = None
        self._house: dict[str, Any] = {}
        self._ids = IdTable({})
        self._types: dict[str, str] = {}
        self._condition = ThorCondition(0.0, 1.0, False)
        self._points = np.empty((0, 2))
        self._spawn = WorldPose(0.0, 0.0, 0.0)
        self._visible: tuple[VisibleObject, ...] = ()
        self._steps = 0
        self._done = False

    # -- THOR calls --------------------------------------------------------------------
    def _start(self, house: dict[str, Any]) -> None:
        options = {**DEFAULTS, **self._user_options}
        options.update(
            scene=house,
            visibilityDistance=self._condition.visibility_distance,
            server_timeout=self._step_timeout,
            server_start_timeout=self._start_timeout,
        )
        if self._factory is None:
            thor = _launch.import_ai2thor()
            options.setdefault("platform", thor.platform.CloudRendering)
            _launch.preflight(thor, options, allow_download=self._allow_download)
            factory: Callable[..., Any] = thor.controller.Controller
        else:
            options.setdefault("platform", "CloudRendering")
            factory = self._factory
        self._controller = _launch.start(factory, options, seconds=self._start_timeout)

    def _call(self, what: str, fn: Callable[[], Any]) -> Any:
        def on_timeout() -> TransportError:
            return TransportError(
                f"AI2-THOR did not answer {what} within step_timeout={self._step_timeout:g} s; "
                "the Unity process hangs or died (see ~/.ai2thor/log/unity.log)."
            )

        try:
            return bounded(fn, seconds=self._step_timeout, on_timeout=on_timeout)
        except TransportError:
            raise
        except Exception as exc:
            raise TransportError(f"AI2-THOR failed on {what}: {type(exc).__name__}: {exc}") from exc

    def _act(self, action: str, **args: Any) -> Any:
        return self._call(action, lambda: self._controller.step(action=action, **args))

    def _teleport(self, pose: WorldPose) -> Any:
        return self._act(
            "TeleportFull",
            position={"x": pose.x, "y": AGENT_Y, "z": pose.z},
            rotation={"x": 0.0, "y": pose.heading, "z": 0.0},
            horizon=0,
            standing=True,
        )

    # -- Simulator protocol ------------------------------------------------------------
    def reset(self, layout: Layout, condition: str, spawn_room: str, seed: int) -> Observation:
        self._condition = thor_condition(condition)
        check_choice("spawn_room", spawn_room, [r.name for r in layout.rooms])
        room = layout.room(spawn_room)
        heading = StableRng(seed).choice((0.0, 90.0, 180.0, 270.0))
        centre = WorldPose((room.x0 + room.x1) / 2, (room.z0 + room.z1) / 2, heading)
        house = build_house(layout, condition, seed, agent=centre, asset_ids=self._asset_ids)
        if self._controller is None:
            self._start(house)
        else:
            vis = self._condition.visibility_distance
            self._call("reset", lambda: self._controller.reset(scene=house, visibilityDistance=vis))
        self._layout, self._house, self._ids = layout, house, IdTable.from_house(house)
        self._types = {o.object_id: o.object_type for o in layout.objects}
        self._points = grid(self._act("GetReachablePositions").metadata["actionReturn"] or [])
        if self._condition.randomize_materials:
            self._act(
                "RandomizeMaterials",
                useTrainMaterials=True,
                useValMaterials=True,
                useTestMaterials=True,
            )
            self._act("RandomizeColors")
        spot = nearest_in_room(self._points, centre.x, centre.z, room)
        if spot is None:
            raise ConfigError(
                f"AI2-THOR reports no reachable position in spawn_room={spawn_room!r}; "
                "check that the build loaded the house (see ~/.ai2thor/log/unity.log)."
            )
        event = self._teleport(WorldPose(spot[0], spot[1], heading))
        if not event.metadata["lastActionSuccess"]:
            raise ConfigError(f"AI2-THOR refused the spawn pose: {event.metadata['errorMessage']}")
        self._spawn = agent_pose(event.metadata)
        self._steps, self._done = 0, False
        return self._observe(True, "Episode started.")

    def step(self, action: str) -> Observation:
        if self._layout is None:
            raise ConfigError("ThorSimulator.step() before reset(); call reset(layout, ...) first.")
        if self._done:
            return self._observe(False, f"{action.strip()} failed: the episode has ended.")
        self._steps += 1
        parsed = _grammar.parse(action)
        if isinstance(parsed, _grammar.Invalid):
            return self._observe(False, f"Action failed: {parsed.reason}.")
        if isinstance(parsed, _grammar.Term):
            return self._term(parsed.room)
        if isinstance(parsed, _grammar.Turn):
            for rotate in ROTATIONS[parsed.direction]:
                self._act(rotate, degrees=90)
            return self._observe(True, f"Turn({parsed.direction}) succeeded.")
        return self._goto(parsed.target)

    def _term(self, room: str) -> Observation:
        assert self._layout is not None
        names = [r.name for r in self._layout.rooms]
        if room not in names:
            return self._observe(False, f"Term({room}) failed: unknown room; name one of {names}.")
        self._done = True
        return self._observe(True, f"Term({room}) accepted.", terminal_room=room)

    def _goto(self, target: str) -> Observation:
        assert self._layout is not None
        wanted = target.strip().lower()
        matches = [
            v for v in self._visible if wanted in (v.object_id.lower(), v.object_type.lower())
        ]
        if not matches:
            return self._observe(False, f"Goto({target}) failed: {target} is not visible.")
        chosen = min(matches, key=lambda v: (v.distance, v.object_id))
        doorway = next((d for d in self._layout.doorways if d.object_id == chosen.object_id), None)
        pose = self._door_pose(doorway) if doorway else self._object_pose(chosen.object_id)
        if pose is None:
            return self._observe(False, f"Goto({target}) failed: no reachable spot near it.")
        event = self._teleport(pose)
        if not event.metadata["lastActionSuccess"]:
            reason = event.metadata.get("errorMessage") or "THOR refused the move"
            return self._observe(False, f"Goto({target}) failed: {reason}.")
        return self._observe(True, f"Goto({chosen.object_id}) succeeded.")

    def _door_pose(self, doorway: Doorway) -> WorldPose | None:
        assert self._layout is not None
        here = self.current_room()
        other = doorway.room_b if here == doorway.room_a else doorway.room_a
        return entry(self._points, doorway, self._layout.room(other))

    def _object_pose(self, object_id: str) -> WorldPose | None:
        assert self._layout is not None
        obj = next(o for o in self._layout.objects if o.object_id == object_id)
        return viewpoint(self._points, obj.x, obj.z, self._layout.room(obj.room))

    def _observe(
        self, success: bool, message: str, *, terminal_room: str | None = None
    ) -> Observation:
        event = self._controller.last_event
        world = agent_pose(event.metadata)
        self._visible = visible_objects(
            event.metadata["objects"],
            world,
            max_distance=self._condition.visibility_distance,
            ids=self._ids,
            types=self._types,
        )
        frame = np.ascontiguousarray(event.frame, dtype=np.uint8)
        if frame.ndim != 3 or frame.shape[2] != 3:
            raise TransportError(f"AI2-THOR returned a frame of shape {frame.shape}, not HxWx3.")
        x, z = to_spawn_frame(self._spawn, world.x, world.z)
        pose = Pose(round(x, 2), round(z, 2), heading_in_spawn_frame(self._spawn, world.heading))
        feedback = (
            f"{message} Pose: x={pose.x:.2f}, z={pose.z:.2f}, heading={pose.heading:.0f} deg."
        )
        return Observation(
            step=self._steps,
            pose=pose,
            success=success,
            feedback=feedback,
            visible=self._visible,
            frame_digest=hashlib.sha256(frame.tobytes()).hexdigest(),
            jpeg=_jpeg(frame),
            frame=frame,
            done=self._done,
            terminal_room=terminal_room,
        )

    @property
    def agent_pose(self) -> WorldPose:
        return agent_pose(self._controller.last_event.metadata)

    @property
    def spawn_pose(self) -> WorldPose:
        return self._spawn

    @property
    def house(self) -> Mapping[str, Any]:
        """The ProcTHOR house of the current episode."""
        return self._house

    def current_room(self) -> str:
        assert self._layout is not None
        pose = self.agent_pose
        room = self._layout.room_at(pose.x, pose.z)
        if room is None:
            raise TransportError(f"AI2-THOR put the agent outside every room at {pose}.")
        return room

    def visible_ids(self) -> tuple[str, ...]:
        return tuple(v.object_id for v in self._visible)

    def close(self) -> None:
        controller, self._controller = self._controller, None
        if controller is not None:
            self._call("stop", controller.stop)
