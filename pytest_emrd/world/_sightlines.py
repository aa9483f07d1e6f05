"""Rays against walls and the visibility test, compiled with numba.

:meth:`pytest_emrd.world._geometry.Walls.first_hit` (the renderer's 512 rays, every wall test
of ``G_base``) and :func:`pytest_emrd.world._visibility.sight` (every step) loop here over
rays, sample points and wall segments in one pass, where the numpy versions they replace
built a (segments x rays) array per axis and ran a dozen whole-array operations on a few
hundred elements (interpreter overhead, not arithmetic, was their cost).

Bit identity with those numpy versions (``tests/world/test_sightlines.py`` keeps them as
oracles): every floating-point value comes from the same exactly rounded IEEE operations
(``+ - * /``, comparisons) on the same operands in the same order; numba without
``fastmath`` neither reorders them nor fuses a multiply and an add, and
``error_model="numpy"`` makes ``x / 0`` give ``inf`` or ``nan`` as numpy does. The nearest
hit is a minimum, which does not depend on the order segments are visited in; a sample
point counts as blocked exactly when some wall hit lies before it, so the test stops at the
first such wall and an object at its first visible sample point.

Imported lazily (by the first wall test), like :mod:`pytest_emrd.world._kernel`, so the
package, the plugin and layout generation never load numba; compiled code is cached on
disk (``cache=True``).
"""

from __future__ import annotations

import numpy as np
from numba import njit

_JIT = {"cache": True, "nogil": True, "error_model": "numpy"}
EPS = 1e-9
"""A hit at ray parameter ``t <= EPS`` is the ray's own origin, not a wall ahead."""


@njit(**_JIT)
def _nearest(across: float, along: float, d_across: float, d_along: float, segs: np.ndarray):
    """Nearest ray parameter ``t > EPS`` at which ``across + t * d_across`` meets a segment
    ``(c, lo, hi)`` (``across == c``, ``lo <= along + t * d_along <= hi``); ``inf`` if none."""
    best = np.inf
    for s in range(segs.shape[0]):
        t = (segs[s, 0] - across) / d_across
        if t > EPS and np.isfinite(t) and t < best:
            hit = along + t * d_along
            if hit >= segs[s, 1] and hit <= segs[s, 2]:
                best = t
    return best


@njit(**_JIT)
def first_hits(
    ox: np.ndarray,
    oz: np.ndarray,
    dx: np.ndarray,
    dz: np.ndarray,
    along_x: np.ndarray,
    along_z: np.ndarray,
    t_out: np.ndarray,
    x_out: np.ndarray,
) -> None:
    """Per ray ``o + t d`` (1-D arrays as long as the outputs, or of one element shared by
    every ray): the nearest wall hit into ``t_out`` (``inf`` if none) and whether that wall
    runs along x into ``x_out`` (True on a tie and when nothing is hit). Walls: rows
    ``(z, x0, x1)`` along x, ``(x, z0, z1)`` along z."""
    for i in range(t_out.size):
        x, z = ox[min(i, ox.size - 1)], oz[min(i, oz.size - 1)]
        ux, uz = dx[min(i, dx.size - 1)], dz[min(i, dz.size - 1)]
        t_x = _nearest(z, x, uz, ux, along_x)
        t_z = _nearest(x, z, ux, uz, along_z)
        t_out[i] = min(t_x, t_z)
        x_out[i] = t_x <= t_z


@njit(**_JIT)
def sight_mask(
    samples: np.ndarray,
    pose: tuple[float, float, float, float, float, float],
    visibility2: float,
    along_x: np.ndarray,
    along_z: np.ndarray,
    mask: np.ndarray,
) -> None:
    """Into ``mask[i]``: whether a sample point ``samples[i, j]`` of object ``i`` lies in the
    field of view (``forward > 0``, ``|lateral| <= forward``), within ``visibility2`` squared
    metres, with no wall hit before it. ``pose``: position ``x, z``, forward ``fx, fz``, right
    ``rx, rz`` (:func:`pytest_emrd.world._visibility.sight`)."""
    px, pz, fx, fz, rx, rz = pose
    for i in range(samples.shape[0]):
        mask[i] = False
        for j in range(samples.shape[1]):
            dx = samples[i, j, 0] - px
            dz = samples[i, j, 1] - pz
            fwd = dx * fx + dz * fz
            lat = dx * rx + dz * rz
            if not (fwd > 0 and abs(lat) <= fwd and dx * dx + dz * dz <= visibility2):
                continue
            t_x = _nearest(pz, px, dz, dx, along_x)
            t_z = _nearest(px, pz, dx, dz, along_z)
            if not min(t_x, t_z) < 1.0 - EPS:
                mask[i] = True
                break
