"""The built-in backend: the numpy world behind the :class:`Simulator` protocol."""

from __future__ import annotations

import hashlib
import io
from collections import OrderedDict
from collections.abc import Mapping

import numpy as np
from PIL import Image

from pytest_emrd.errors import ConfigError, check_choice, check_range
from pytest_emrd.rooms import ROOM_NAMES, SLUG_ROOMS
from pytest_emrd.trajectory import Pose
from pytest_emrd.world._actions import GRAMMAR, TURNS, Action, normalise, parse_action
from pytest_emrd.world._conditions import ConditionParams, condition_params
from pytest_emrd.world._geometry import heading_in_spawn_frame, to_spawn_frame
from pytest_emrd.world._model import Layout, Observation, WorldPose
from pytest_emrd.world._motion import approach, spawn_pose, through
from pytest_emrd.world._render import palette, render, shade_table
from pytest_emrd.world._scene import Scene, scene_of
from pytest_emrd.world._visibility import Sight, sight

JPEG_QUALITY = 85
FRAME_CACHE = 16
"""Frames kept per episode (least recently used dropped first)."""


class _Failed(Exception):
    """An action that could not be executed; the message is the reason shown to the agent."""


class BuiltinSimulator:
    """Pure-numpy office simulator: semantic actions, wall-occluded visibility, ray-cast frames.

    ``room_aliases`` maps extra names ``Term`` accepts to canonical room names (for prompt
    variants that rename the rooms, e.g. ``{"Room A": "Office"}``). ``frame_cache`` is how
    many recent frames of an episode are kept for poses the agent returns to (0: none).
    """

    def __init__(
        self,
        *,
        room_aliases: Mapping[str, str] | None = None,
        jpeg_quality: int = JPEG_QUALITY,
        frame_cache: int = FRAME_CACHE,
    ) -> None:
        self._rooms = {normalise(r): r for r in ROOM_NAMES}
        for alias, room in (room_aliases or {}).items():
            check_choice(f"room_aliases[{alias!r}]", room, ROOM_NAMES)
            self._rooms[normalise(alias)] = room
        self._quality = check_range("jpeg_quality", jpeg_quality, 1, 95)
        if isinstance(frame_cache, bool) or not isinstance(frame_cache, int) or frame_cache < 0:
            raise ConfigError(
                f"frame_cache={frame_cache!r} must be a whole number >= 0 (0 turns the cache off)."
            )
        self._cache_size = frame_cache
        self._scene: Scene | None = None
        self._params: ConditionParams = condition_params("baseline")
        self._table = np.zeros((0, 3), dtype=np.uint8)
        self._pose = WorldPose(0.0, 0.0, 0.0)
        self._spawn = self._pose
        self._steps = 0
        self._terminal: str | None = None
        self._sight: Sight | None = None
        self._frames: OrderedDict[WorldPose, tuple[np.ndarray, str, bytes]] = OrderedDict()

    # -- protocol ---------------------------------------------------------------------
    def reset(self, layout: Layout, condition: str, spawn_room: str, seed: int) -> Observation:
        """Start an episode in ``spawn_room`` (canonical name or slug) under ``condition``."""
        room = SLUG_ROOMS.get(spawn_room, spawn_room)
        check_choice("spawn_room", room, [*ROOM_NAMES, *SLUG_ROOMS])
        self._params = condition_params(condition)
        self._scene = scene_of(layout)
        self._table = shade_table(palette(self._scene, self._params, seed), self._params)
        self._spawn = self._pose = spawn_pose(self._scene, layout.room(room), seed)
        self._steps, self._terminal = 0, None
        self._sight = None
        self._frames.clear()
        return self._observe(True, "Episode started.")

    def step(self, action: str) -> Observation:
        """Execute one action text; never raises for a bad action (the step is consumed)."""
        scene = self._require()
        self._steps += 1
        parsed = parse_action(action)
        shown = str(parsed) if parsed else "Action"
        try:
            if self._terminal is not None:
                raise _Failed("the episode is over")
            if parsed is None:
                text = " ".join(action.split())[:80]
                raise _Failed(f"could not read {text!r}; use {GRAMMAR}")
            note = {"Goto": self._goto, "Turn": self._turn, "Term": self._term}[parsed.verb](
                scene, parsed
            )
        except _Failed as failure:
            return self._observe(False, f"{shown} failed: {failure}.")
        return self._observe(True, f"{shown} succeeded{note}.")

    @property
    def agent_pose(self) -> WorldPose:
        self._require()
        return self._pose

    @property
    def spawn_pose(self) -> WorldPose:
        self._require()
        return self._spawn

    def current_room(self) -> str:
        scene = self._require()
        room = scene.layout.room_at(self._pose.x, self._pose.z)
        if room is None:  # unreachable: every pose the world produces is inside a room
            raise ConfigError(f"agent pose={self._pose} lies outside every room of the layout.")
        return room

    def visible_ids(self) -> tuple[str, ...]:
        scene = self._require()
        return tuple(v.object_id for v in self._current_sight().listing(scene))

    def close(self) -> None:
        self._scene = None
        self._frames.clear()

    # -- actions ----------------------------------------------------------------------
    def _goto(self, scene: Scene, action: Action) -> str:
        if not action.arg:
            raise _Failed("Goto needs a target: an object id such as Desk_2 or a type")
        key = normalise(action.arg)
        seen = self._current_sight()
        visible = [int(i) for i in np.flatnonzero(seen.mask)]
        objs = scene.layout.objects
        matches = [i for i in visible if normalise(objs[i].object_id) == key]
        if not matches:
            typed = [i for i in visible if normalise(objs[i].object_type) == key]
            matches = sorted(typed, key=lambda i: (seen.distance[i], objs[i].object_id))[:1]
        if not matches:
            listed = ", ".join(v.object_id for v in seen.listing(scene)) or "nothing"
            raise _Failed(f"no visible object matches {action.arg!r}. Visible: {listed}")
        target = objs[matches[0]]
        if target.object_type == "Doorway":
            doorway = next(d for d in scene.layout.doorways if d.object_id == target.object_id)
            pose = through(scene, doorway, self._pose, self.current_room())
        else:
            pose = approach(scene, matches[0], self._pose)
        if pose is None:
            raise _Failed(f"there is no free spot to stand at {target.object_id}")
        self._move(pose)
        return "" if normalise(target.object_id) == key else f": moved to {target.object_id}"

    def _turn(self, scene: Scene, action: Action) -> str:
        delta = TURNS.get(normalise(action.arg))
        if delta is None:
            raise _Failed(
                f"cannot turn {action.arg!r}; use Turn(Left), Turn(Right) or Turn(Around)"
            )
        self._move(WorldPose(self._pose.x, self._pose.z, (self._pose.heading + delta) % 360))
        return ""

    def _term(self, scene: Scene, action: Action) -> str:
        room = self._rooms.get(normalise(action.arg))
        if room is None:
            names = ", ".join(ROOM_NAMES)
            raise _Failed(f"{action.arg!r} is not a room of this building; name one of {names}")
        self._terminal = room
        return ": the episode is over"

    # -- observation ------------------------------------------------------------------
    def _require(self) -> Scene:
        if self._scene is None:
            raise ConfigError("BuiltinSimulator used before reset(); call reset(...) first.")
        return self._scene

    def _move(self, pose: WorldPose) -> None:
        self._pose = pose
        self._sight = None

    def _current_sight(self) -> Sight:
        if self._sight is None:
            self._sight = sight(self._require(), self._pose, self._params.visibility_distance)
        return self._sight

    def _spawn_frame_pose(self) -> Pose:
        x, z = to_spawn_frame(self._spawn, self._pose.x, self._pose.z)
        heading = heading_in_spawn_frame(self._spawn, self._pose.heading)
        return Pose(round(x, 4) + 0.0, round(z, 4) + 0.0, heading)

    def _render(self) -> tuple[np.ndarray, str, bytes]:
        """Frame, pixel digest and JPEG of the current pose; agents often come back to a
        pose (a full sweep ends where it began), so recent frames of the episode are kept."""
        cached = self._frames.get(self._pose)
        if cached is not None:
            self._frames.move_to_end(self._pose)
            return cached
        frame = render(self._require(), self._pose, self._params, self._table)
        frame.setflags(write=False)  # shared with the cache
        buf = io.BytesIO()
        Image.fromarray(frame).save(buf, format="JPEG", quality=self._quality)
        entry = (frame, hashlib.sha256(frame.tobytes()).hexdigest(), buf.getvalue())
        self._frames[self._pose] = entry
        while len(self._frames) > self._cache_size:
            self._frames.popitem(last=False)
        return entry

    def _observe(self, success: bool, message: str) -> Observation:
        scene = self._require()
        pose = self._spawn_frame_pose()
        frame, digest, jpeg = self._render()
        feedback = f"{message} Pose: x={_fmt(pose.x)} z={_fmt(pose.z)} heading={pose.heading:.0f}."
        return Observation(
            step=self._steps,
            pose=pose,
            success=success,
            feedback=feedback,
            visible=self._current_sight().listing(scene),
            frame_digest=digest,
            jpeg=jpeg,
            frame=frame,
            done=self._terminal is not None,
            terminal_room=self._terminal,
        )


def _fmt(value: float) -> str:
    """Centimetre text of a coordinate, never ``-0.00``."""
    return f"{round(value, 2) + 0.0:.2f}"
