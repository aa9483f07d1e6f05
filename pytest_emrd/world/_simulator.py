"""The built-in backend: the numpy world behind the :class:`Simulator` protocol."""

from __future__ import annotations

import functools
import hashlib
import threading
from collections import OrderedDict
from collections.abc import Mapping
from typing import Any

import numpy as np

from pytest_emrd._lazy import remember
from pytest_emrd.errors import ConfigError, check_range
from pytest_emrd.world._conditions import ConditionParams, condition_params
from pytest_emrd.world._feedback import (
    Action,
    SemanticStep,
    room_table,
    spawn_room_name,
    turn_degrees,
)
from pytest_emrd.world._model import Layout, Observation, View, VisibleObject, WorldPose
from pytest_emrd.world._motion import approach, spawn_pose, through
from pytest_emrd.world._render import palette, render, shade_table
from pytest_emrd.world._scene import Scene, scene_of
from pytest_emrd.world._visibility import in_view

JPEG_QUALITY = 85
FRAME_CACHE = 16
"""Frames kept per episode (least recently used dropped first)."""
VIEW_DIGESTS = 1 << 16
"""Views whose pixel digest this process knows (a few hundred bytes each)."""
SHADE_TABLES = 64
"""Shade tables kept (one per condition of a layout; under ``texture`` one per seed)."""

_lock = threading.Lock()
_Seen = tuple[str, tuple[VisibleObject, ...]]
"""A view's pixel digest and the objects it shows legibly."""
#: (scene, id of a shade table, pose) -> the table and the view's digest and visible objects
#: (the entry holds the table, so its id is not reused while the entry lives). Scenes hash
#: by identity: an entry is only found with the memoised scene object it was made with.
_digests: OrderedDict[tuple[Scene, int, WorldPose], tuple[np.ndarray, _Seen]] = OrderedDict()
#: (scene, condition, ``texture`` seed or None) -> shade table.
_tables: OrderedDict[tuple[Scene, ConditionParams, int | None], np.ndarray] = OrderedDict()


def _remember(table: OrderedDict[Any, Any], key: Any, value: Any, capacity: int) -> None:
    with _lock:
        remember(table, key, value, capacity)


def forget_views() -> None:
    """Forget every remembered view digest and shade table, as in a new process."""
    with _lock:
        _digests.clear()
        _tables.clear()


def _shades(scene: Scene, params: ConditionParams, seed: int) -> np.ndarray:
    """The episode's shade table, one object per scene, condition and (``texture``) seed."""
    key = (scene, params, seed if params.randomize_palette else None)
    table = _tables.get(key)
    if table is None:
        table = shade_table(palette(scene, params, seed), params, scene.owners)
        _remember(_tables, key, table, SHADE_TABLES)
    return table


class BuiltinSimulator(SemanticStep):
    """Built-in office simulator: semantic actions, ray-cast frames, visibility read off them.

    ``room_aliases`` maps extra names ``Term`` accepts to canonical room names (``{"Room A":
    "Office"}``). ``frame_cache`` is how many recent frames of an episode are kept (0: only
    the current one).

    :param room_aliases: Extra room name -> canonical room, for ``Term``.
    :param jpeg_quality: JPEG quality of the frames, 1-95.
    :param frame_cache: Recent frames kept per episode.
    """

    def __init__(
        self,
        *,
        room_aliases: Mapping[str, str] | None = None,
        jpeg_quality: int = JPEG_QUALITY,
        frame_cache: int = FRAME_CACHE,
    ) -> None:
        self._rooms = room_table(room_aliases)
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
        self._frames: OrderedDict[WorldPose, tuple[_Seen, View]] = OrderedDict()

    def reset(
        self, layout: Layout, condition: str, spawn_room: str, seed: int, *, symbolic: bool = True
    ) -> Observation:
        """Start an episode in ``spawn_room`` (canonical name or slug) under ``condition``."""
        room = spawn_room_name(spawn_room)
        self._params = condition_params(condition)
        self._scene = scene_of(layout)
        self._table = _shades(self._scene, self._params, seed)
        self._spawn = self._pose = spawn_pose(self._scene, layout.room(room), seed)
        self._frames.clear()
        return self._begin(symbolic)

    @property
    def agent_pose(self) -> WorldPose:
        self._require()
        return self._pose

    def current_room(self) -> str:
        scene = self._require()
        room = scene.layout.room_at(self._pose.x, self._pose.z)
        if room is None:  # unreachable: every pose the world produces is inside a room
            raise ConfigError(f"agent pose={self._pose} lies outside every room of the layout.")
        return room

    def close(self) -> None:
        self._scene = None
        self._frames.clear()

    def _in_view(self) -> tuple[VisibleObject, ...]:
        return self._render()[0][1]

    def _reach(self, object_id: str) -> bool:
        scene = self._require()
        doorway = next((d for d in scene.layout.doorways if d.object_id == object_id), None)
        if doorway is None:
            pose = approach(scene, scene.index[object_id], self._pose)
        else:
            pose = through(scene, doorway, self._pose, self.current_room())
        if pose is not None:
            self._pose = pose
        return pose is not None

    def _turn(self, action: Action) -> str:
        delta = turn_degrees(action)
        self._pose = WorldPose(self._pose.x, self._pose.z, (self._pose.heading + delta) % 360)
        return ""

    def _require(self) -> Scene:
        if self._scene is None:
            raise ConfigError("BuiltinSimulator used before reset(); call reset(...) first.")
        return self._scene

    def _render(self) -> tuple[_Seen, View]:
        """Pixel digest, visible objects and view of the current pose. The views of recent
        poses are kept (a sweep ends where it began); the process remembers each view's
        digest and visible objects per shared scene and shade table, so a view seen before is
        drawn only if its pixels or JPEG are read (not under ``texture``). ``frame_cache=0``
        turns both off."""
        pose, scene, table = self._pose, self._require(), self._table
        cached = self._frames.get(pose)
        if cached is not None:
            self._frames.move_to_end(pose)
            return cached
        draw = functools.partial(render, scene, pose, self._params, table)
        # A texture episode's table is its own: no other episode can share its views.
        shared = self._cache_size > 0 and not self._params.randomize_palette
        key = (scene, id(table), pose)
        known = _digests.get(key) if shared else None
        if known is not None and known[0] is table:
            entry = known[1], View(lambda: draw()[0], self._quality)
        else:
            pixels, legible = draw()
            seen = hashlib.sha256(pixels.data).hexdigest(), in_view(scene, pose, legible)
            entry = seen, View.of(pixels, self._quality)
            if shared:
                _remember(_digests, key, (table, seen), VIEW_DIGESTS)
        remember(self._frames, pose, entry, max(self._cache_size, 1))  # the current view, at least
        return entry

    def _view(self) -> tuple[WorldPose, tuple[VisibleObject, ...], str, View]:
        (digest, visible), view = self._render()
        return self._pose, visible, digest, view
