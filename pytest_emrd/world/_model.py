"""Data model of the world stage: the layout every backend builds, and what a step returns.

World frame: metres, ``x`` east, ``z`` north, headings in degrees clockwise from north
(``+z``, AI2-THOR's yaw). The office spans ``[0, width] x [0, depth]``.
"""

from __future__ import annotations

from collections.abc import Callable
from dataclasses import dataclass, field
from typing import Protocol

import numpy as np

from pytest_emrd.trajectory import Pose


@dataclass(frozen=True)
class Room:
    """An axis-aligned rectangular room."""

    name: str
    """Canonical room name (see :mod:`pytest_emrd.rooms`)."""
    x0: float
    z0: float
    x1: float
    z1: float

    @property
    def centre(self) -> tuple[float, float]:
        """The ``(x, z)`` centre of the floor."""
        return (self.x0 + self.x1) / 2, (self.z0 + self.z1) / 2

    def contains(self, x: float, z: float) -> bool:
        return self.x0 <= x <= self.x1 and self.z0 <= z <= self.z1


@dataclass(frozen=True)
class Doorway:
    """A gap in the wall shared by two rooms."""

    object_id: str
    """Instance id, also the ``Goto`` target (``Doorway_1``)."""
    room_a: str
    room_b: str
    x: float
    z: float
    width: float
    axis: str
    """``"x"`` if the wall runs along x (gap spans x), ``"z"`` if it runs along z."""


@dataclass(frozen=True)
class WorldObject:
    """A piece of furniture, a fixture or a landmark (doorways are also listed here)."""

    object_id: str
    """``Type_N`` instance id, unique in the layout."""
    object_type: str
    """AI2-THOR ``objectType`` name."""
    room: str
    category: str
    """``landmark``, ``salient`` or ``clutter``."""
    x: float
    """Centre of the footprint."""
    z: float
    width: float
    """Extent along the object's own x axis (before rotation)."""
    depth: float
    height: float
    rotation: float = 0.0
    """Yaw in degrees; 0/90/180/270 only, so footprints stay axis-aligned."""
    color: tuple[int, int, int] = (128, 128, 128)
    elevation: float = 0.0
    """Height of the base above the floor (a laptop on a desk); the object spans
    ``[elevation, elevation + height]``."""


@dataclass(frozen=True)
class Layout:
    """One office: the single source of truth for every backend."""

    seed: int
    width: float
    depth: float
    rooms: tuple[Room, ...]
    doorways: tuple[Doorway, ...]
    objects: tuple[WorldObject, ...]
    """Every object, doorways and the building exit included."""
    wall_thickness: float = 0.1
    version: int = 1

    def room(self, name: str) -> Room:
        for r in self.rooms:
            if r.name == name:
                return r
        raise KeyError(name)

    def room_at(self, x: float, z: float) -> str | None:
        return next((r.name for r in self.rooms if r.contains(x, z)), None)

    def inventory(self) -> dict[str, dict[str, int]]:
        """Room name -> object type -> count, doorways excluded (the prompt's room overview)."""
        table: dict[str, dict[str, int]] = {r.name: {} for r in self.rooms}
        for o in self.objects:
            if o.object_type != "Doorway":
                table[o.room][o.object_type] = table[o.room].get(o.object_type, 0) + 1
        return table


@dataclass(frozen=True)
class WorldPose:
    """Agent pose in the world frame."""

    x: float
    z: float
    heading: float


@dataclass(frozen=True)
class VisibleObject:
    """One object in view, as the symbolic (``text``) modality reports it."""

    object_id: str
    object_type: str
    bearing: float
    """Degrees, negative to the left of the view axis, within [-45, 45]."""
    distance: float
    """Metres from the agent to the object's centre."""


class View:
    """One view's read-only RGB pixels and their JPEG, each made on first use and kept (a
    replay sends frames by digest and needs neither; two threads may both make one)."""

    __slots__ = ("_draw", "_jpeg", "_pixels", "_quality")

    def __init__(self, draw: Callable[[], np.ndarray], quality: int) -> None:
        self._draw, self._quality = draw, quality
        self._pixels: np.ndarray | None = None
        self._jpeg: bytes | None = None

    @classmethod
    def of(cls, pixels: np.ndarray, quality: int) -> View:
        """The view of pixels already drawn."""
        view = cls(lambda: pixels, quality)
        view._keep(pixels)
        return view

    def _keep(self, pixels: np.ndarray) -> np.ndarray:
        pixels.setflags(write=False)  # shared by every observation of the view
        self._pixels = pixels
        return pixels

    @property
    def pixels(self) -> np.ndarray:
        """The ``(H, W, 3)`` uint8 frame."""
        return self._keep(self._draw()) if self._pixels is None else self._pixels

    @property
    def jpeg(self) -> bytes:
        """The frame as the JPEG the model is sent."""
        if self._jpeg is None:
            from pytest_emrd.world import _jpeg  # Pillow: imported by the first JPEG only

            self._jpeg = _jpeg.encode_jpeg(self.pixels, self._quality)
        return self._jpeg


@dataclass(frozen=True)
class Observation:
    """What the world returns from ``reset`` and ``step``. ``frame_digest`` is the SHA-256 of
    the raw pixels: cassettes key frames by it, not by JPEG bytes (stable across Pillow)."""

    step: int
    """Actions executed so far (0 after reset)."""
    pose: Pose
    """Agent pose in the *spawn* frame (the perfect odometry the agent is given)."""
    success: bool
    """Whether the last action succeeded (True after reset)."""
    feedback: str
    """Engine feedback text: action result and pose; never names the room."""
    visible: tuple[VisibleObject, ...]
    """Objects in view, sorted by object id."""
    frame_digest: str
    view: View = field(repr=False, compare=False)
    done: bool = False
    """True once a Term was executed (whatever room it named)."""
    terminal_room: str | None = None
    """The canonical room the Term named, or None (no Term yet, or Other)."""

    @property
    def frame(self) -> np.ndarray:
        """The ``512 x 512 x 3`` uint8 frame (read-only)."""
        return self.view.pixels

    @property
    def jpeg(self) -> bytes:
        """The frame as the JPEG the model is sent."""
        return self.view.jpeg


class Simulator(Protocol):
    """The interface both backends (``builtin``, ``ai2thor``) implement."""

    def reset(
        self, layout: Layout, condition: str, spawn_room: str, seed: int, *, symbolic: bool = True
    ) -> Observation:
        """Place the agent in ``spawn_room`` and return the first observation (``symbolic=False``:
        the ``vision`` modality, no feedback names an object id)."""
        ...

    def step(self, action: str) -> Observation:
        """Execute one action text; an invalid one is consumed and the observation says why."""
        ...

    @property
    def agent_pose(self) -> WorldPose:
        """Ground-truth pose in the world frame."""
        ...

    @property
    def spawn_pose(self) -> WorldPose:
        """Where the episode started, world frame (defines the spawn frame)."""
        ...

    def current_room(self) -> str:
        """Ground-truth room of the agent."""
        ...

    def visible_ids(self) -> tuple[str, ...]:
        """Ground-truth ids visible now (sorted)."""
        ...

    def close(self) -> None: ...
