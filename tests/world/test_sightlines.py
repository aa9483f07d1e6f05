"""The compiled wall and visibility tests against the numpy code they replaced (kept here as
oracles): the same ``t`` bits, the same wall axis, the same visible objects, bearings and
distances, for random walls and rays and for poses all over generated offices."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pytest_emrd.world import WorldPose, generate_layout, paper_office
from pytest_emrd.world._geometry import Walls, right_of, unit
from pytest_emrd.world._scene import Scene, scene_of
from pytest_emrd.world._visibility import HALF_FOV, sight


def _hits_oracle(across, along, d_across, d_along, segs):  # type: ignore[no-untyped-def]
    if segs.size == 0:
        return np.full(np.broadcast(across, d_across).shape, np.inf)
    lead = (-1,) + (1,) * np.broadcast(across, along, d_across, d_along).ndim
    c, lo, hi = (segs[:, i].reshape(lead) for i in range(3))
    with np.errstate(divide="ignore", invalid="ignore"):
        t = (c - across) / d_across
        hit = along + t * d_along
    ok = (t > 1e-9) & (hit >= lo) & (hit <= hi) & np.isfinite(t)
    return np.where(ok, t, np.inf).min(axis=0)


def _first_hit_oracle(walls: Walls, ox, oz, dx, dz):  # type: ignore[no-untyped-def]
    t_x = _hits_oracle(oz, ox, dz, dx, walls.along_x)
    t_z = _hits_oracle(ox, oz, dx, dz, walls.along_z)
    return np.minimum(t_x, t_z), t_x <= t_z


def _sight_oracle(scene: Scene, pose: WorldPose, visibility: float):  # type: ignore[no-untyped-def]
    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    dx = scene.samples[..., 0] - pose.x
    dz = scene.samples[..., 1] - pose.z
    fwd = dx * fx + dz * fz
    lat = dx * rx + dz * rz
    cand = (fwd > 0) & (np.abs(lat) <= fwd) & (dx * dx + dz * dz <= visibility * visibility)
    idx = np.nonzero(cand)
    if idx[0].size:
        pts = scene.samples[idx]
        ox, oz = np.float64(pose.x), np.float64(pose.z)
        t, _ = _first_hit_oracle(scene.walls, ox, oz, pts[:, 0] - ox, pts[:, 1] - oz)
        blocked = t < 1.0 - 1e-9
        cand[idx[0][blocked], idx[1][blocked]] = False
    cx = scene.centres[:, 0] - pose.x
    cz = scene.centres[:, 1] - pose.z
    bearing = np.degrees(np.arctan2(cx * rx + cz * rz, cx * fx + cz * fz))
    return cand.any(axis=1), np.clip(bearing, -HALF_FOV, HALF_FOV), np.hypot(cx, cz)


_grid = st.integers(-20, 120).map(lambda i: i / 10)  # walls and points on a 10 cm grid
_coord = st.one_of(_grid, st.floats(-2, 12, allow_nan=False).map(lambda v: round(v, 2)))
_direction = st.one_of(
    st.sampled_from([-1.0, 0.0, 1.0]),
    st.floats(-2, 2, allow_nan=False, allow_subnormal=False),
    st.integers(0, 511).map(lambda c: (c + 0.5 - 256) / 256),  # the renderer's ray slopes
)
_segment = st.tuples(_grid, _grid, _grid).map(lambda s: (s[0], min(s[1:]), max(s[1:])))
_walls = st.tuples(st.lists(_segment, max_size=8), st.lists(_segment, max_size=8)).map(
    lambda w: Walls(*(np.array(rows, dtype=float).reshape(-1, 3) for rows in w))
)


@settings(max_examples=300)
@given(_walls, st.lists(st.tuples(_coord, _coord, _direction, _direction), min_size=1))
def test_first_hit_is_the_numpy_oracle_bit_for_bit(walls: Walls, rays: list) -> None:
    ox, oz, dx, dz = (np.array(column, dtype=float) for column in zip(*rays, strict=True))
    t, along_x = walls.first_hit(ox, oz, dx, dz)
    t_ref, along_x_ref = _first_hit_oracle(walls, ox, oz, dx, dz)
    assert t.tobytes() == t_ref.tobytes()
    assert np.array_equal(along_x, along_x_ref)


@given(_walls, _coord, _coord, st.lists(st.tuples(_direction, _direction), min_size=1))
def test_first_hit_broadcasts_one_origin_over_many_rays(
    walls: Walls, x: float, z: float, rays: list
) -> None:
    ox, oz = np.float64(x), np.float64(z)
    dx, dz = (np.array(column, dtype=float)[:, None] for column in zip(*rays, strict=True))
    t, along_x = walls.first_hit(ox, oz, dx, dz.T)  # (R, 1) and (1, R): an (R, R) grid
    t_ref, along_x_ref = _first_hit_oracle(walls, ox, oz, dx, dz.T)
    assert t.shape == t_ref.shape == (len(rays), len(rays))
    assert t.tobytes() == t_ref.tobytes()
    assert np.array_equal(along_x, along_x_ref)


def test_first_hit_worked_example() -> None:
    # one wall along x at z=2 from x=0 to 4; one along z at x=3 from z=0 to 1
    walls = Walls(np.array([[2.0, 0.0, 4.0]]), np.array([[3.0, 0.0, 1.0]]))
    t, along_x = walls.first_hit(
        np.array([1.0, 1.0, 1.0, 5.0]),
        np.array([0.5, 0.5, 0.5, 0.5]),
        np.array([0.0, 1.0, -1.0, 0.0]),
        np.array([1.0, 0.0, 0.0, 1.0]),
    )
    assert t.tolist() == [1.5, 2.0, np.inf, np.inf]  # north to the wall; east to x=3; misses
    assert along_x.tolist() == [True, False, True, True]
    assert walls.blocks(np.float64(1.0), np.float64(0.5), np.array([1.0]), np.array([3.0]))[0]


@settings(max_examples=120)
@given(
    st.integers(0, 40),
    st.floats(0, 1),
    st.floats(0, 1),
    st.one_of(st.sampled_from([0.0, 90.0, 180.0, 270.0]), st.floats(0, 359.9)),
    st.sampled_from([3.5, 7.0, 8.0, 12.5]),
)
def test_sight_is_the_numpy_oracle_bit_for_bit(
    seed: int, fx: float, fz: float, heading: float, visibility: float
) -> None:
    layout = paper_office() if seed == 0 else generate_layout(seed)
    x, z = round(fx * layout.width, 2), round(fz * layout.depth, 2)
    pose = WorldPose(x, z, heading)
    scene = scene_of(layout)
    seen = sight(scene, pose, visibility)
    mask, bearing, distance = _sight_oracle(scene, pose, visibility)
    assert np.array_equal(seen.mask, mask)
    assert seen.bearing.tobytes() == bearing.tobytes()
    assert seen.distance.tobytes() == distance.tobytes()
