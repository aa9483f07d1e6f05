"""The first-person frame: a ray-caster, one ray per image column.

Camera: 512 x 512 pixels, 90 degree field of view horizontally and vertically, eye 1.5 m
above the floor, looking level; column ``c`` casts the ray ``forward + right * u`` with
``u = (c + 0.5 - 256) / 256``, so its parameter ``t`` is the depth along the view axis.

Drawing order: ceiling, floor (per-room colour, 0.5 m tiles) and walls (per-room colour,
skirting board, shaded by orientation) fill the frame; then the boxes of every object
within the visibility distance are painted back to front (objects by distance, items on
a desk or counter right after it, boxes bottom-up), each only over the columns it covers
and only where it is nearer than the wall. A box shows its front face, its top face when
below the eye, its underside when above. Surfaces are shaded by orientation and the
condition's light factor, then mixed with fog by depth (see
:mod:`pytest_emrd.world._conditions`).

Bit stability: headings are multiples of 90 degrees and positions centimetre values, so
every geometric quantity comes from ``+ - * /``, comparisons, ``ceil`` and integer casts
only (exactly rounded IEEE operations, no transcendental functions); colours come from a
look-up table built with explicit rounding (``np.rint``) and indexed by integer codes
(each pixel one ``(label * 4 + face) << 8 | fog`` code whose ``R, G, B`` bytes are copied
from the table: no arithmetic on colours). The same scene therefore renders to identical
bytes on every machine and numpy version.

Division of labour: the rays are cast to the walls by
:meth:`~pytest_emrd.world._geometry.Walls.first_hit` (shared with visibility), the boxes in
view picked and ordered by :func:`~pytest_emrd.world._paint.object_boxes`, and the compiled
:func:`~pytest_emrd.world._kernel.compose` does the rest per column and per pixel: where walls
and boxes begin and end, their codes, and the pixels. All three are numba kernels; this
module only hands them the scene's arrays.
"""

from __future__ import annotations

import functools
import io
import threading

import numpy as np
from PIL import Image

from pytest_emrd.world._catalog import WALL_HEIGHT
from pytest_emrd.world._conditions import ConditionParams
from pytest_emrd.world._geometry import right_of, unit
from pytest_emrd.world._model import WorldPose
from pytest_emrd.world._paint import (
    BOTTOM_FACE,
    EYE,
    FOCAL,
    HORIZON,
    NEAR,
    SIZE,
    TOP_FACE,
    X_FACE,
    Z_FACE,
    object_boxes,
)
from pytest_emrd.world._rng import StableRng
from pytest_emrd.world._scene import (
    CEILING,
    FLOOR0,
    PART0,
    RASTER,
    SKIRTING,
    TILE0,
    WALL0,
    Scene,
)

SKIRTING_HEIGHT = 0.1
WALL_BACK = 0.05
"""Metres before a wall hit where the wall's room is looked up (the side the eye is on)."""
FACE_LIGHT = np.array([0.74, 0.9, 1.0, 0.5])
"""Brightness of faces across x, across z, tops and undersides (``_paint.X_FACE`` ...)."""

_U = (np.arange(SIZE) + 0.5 - FOCAL) / FOCAL
_ROWS = np.arange(SIZE, dtype=np.int32)
_CAMERA = (
    FOCAL * (WALL_HEIGHT - EYE) / (HORIZON - (_ROWS[:HORIZON] + 0.5)),
    FOCAL * EYE / ((_ROWS[HORIZON:] + 0.5) - HORIZON),
    FOCAL * (WALL_HEIGHT - EYE),
    FOCAL * (EYE - SKIRTING_HEIGHT),
    FOCAL * EYE,
    NEAR,
    WALL_BACK,
)
""":data:`pytest_emrd.world._kernel.Camera`: the depth of each ceiling and floor row, the
wall's top, the skirting's top and the wall's foot as ``focal * height above or below the
eye``, the near plane, how far before a wall its room is looked up."""
_LABELS = (CEILING, SKIRTING, WALL0, X_FACE, Z_FACE, TOP_FACE, BOTTOM_FACE)


def palette(scene: Scene, params: ConditionParams, seed: int) -> np.ndarray:
    """``(L, 3)`` colours: the catalogue's, or under ``texture`` seeded random colours for
    walls, floors and every object material (ceiling and skirting kept)."""
    colors = scene.colors.astype(np.int64)
    if not params.randomize_palette:
        return colors
    labels = [label for label in range(WALL0, len(colors)) if not TILE0 <= label < PART0]
    colors[labels] = StableRng(seed * 7919 + 17).integers(20, 235, (len(labels), 3))
    colors[TILE0:PART0] = np.maximum(colors[FLOOR0:TILE0] - 12, 0)
    return colors


def shade_table(colors: np.ndarray, params: ConditionParams) -> np.ndarray:
    """``(L * 4 * 256,)`` look-up table: final RGB of ``(label, face, fog weight)``, each
    entry one ``uint32`` ``R | G << 8 | B << 16`` (one gather per pixel).

    ``rgb = rint(colour * face_light * light_factor * (255 - fog) / 255 + fog_rgb * fog / 255)``
    """
    from pytest_emrd.world._kernel import shade  # numba: loaded on first use

    weight = np.arange(256, dtype=np.float64)
    haze = np.array(params.fog_color, dtype=np.float64) * (weight / 255.0)[:, None]
    table = np.empty(len(colors) * len(FACE_LIGHT) * len(weight), dtype=np.uint32)
    light = FACE_LIGHT * params.light_factor
    shade(np.asarray(colors), light, (255.0 - weight) / 255.0, haze, table)
    return table


def render(scene: Scene, pose: WorldPose, params: ConditionParams, table: np.ndarray) -> np.ndarray:
    """The ``(512, 512, 3)`` uint8 frame seen from ``pose`` (``table`` from :func:`shade_table`)."""
    from pytest_emrd.world._kernel import compose  # numba: loaded on the first frame only

    dx, dz = _rays(pose.heading)
    ox, oz = np.float64(pose.x), np.float64(pose.z)
    t_wall, along_x = scene.walls.first_hit(ox, oz, dx, dz)
    view = (dx, dz, np.minimum(t_wall, 1e3), along_x, ox, oz)
    rooms = (scene.floor_raster, scene.room_raster, float(RASTER))
    boxes = object_boxes(scene, pose, params)
    fog = (params.draw_distance, params.fog)
    frame = np.empty((SIZE, SIZE, 3), dtype=np.uint8)
    compose(frame, _buffer(), table, view, rooms, boxes, _CAMERA, _LABELS, fog)
    return frame


@functools.lru_cache(maxsize=16)
def _rays(heading: float) -> tuple[np.ndarray, np.ndarray]:
    """Direction ``forward + right * u`` of each column's ray at ``heading`` (shared by every
    frame at that heading; nothing writes to them)."""
    fx, fz = unit(heading)
    rx, rz = right_of(heading)
    return fx + rx * _U, fz + rz * _U


def encode_jpeg(frame: np.ndarray, quality: int) -> bytes:
    """``frame`` as the JPEG at ``quality`` the model is sent."""
    out = io.BytesIO()
    Image.fromarray(frame).save(out, format="JPEG", quality=quality)
    return out.getvalue()


_LOCAL = threading.local()


def _buffer() -> np.ndarray:
    """This thread's uint32 scratch frame, rows padded by one cache line (a fresh megabyte
    per frame would cost page faults; nothing in it outlives a call to :func:`render`)."""
    buf: np.ndarray | None = getattr(_LOCAL, "buffer", None)
    if buf is None:
        buf = _LOCAL.buffer = np.empty((SIZE, SIZE + 16), dtype=np.uint32)
    return buf
