"""The compiled box selection against the numpy code it replaced (kept here as the oracle):
the same boxes, columns, planes, labels and draw order for poses all over generated
offices, under every condition's visibility distance."""

from __future__ import annotations

import numpy as np
from hypothesis import given, settings
from hypothesis import strategies as st

from pytest_emrd.trajectory import CONDITIONS
from pytest_emrd.world import Layout, WorldPose, condition_params, generate_layout, paper_office
from pytest_emrd.world._conditions import ConditionParams
from pytest_emrd.world._geometry import right_of, unit
from pytest_emrd.world._paint import EYE, FOCAL, NEAR, SIZE, object_boxes
from pytest_emrd.world._scene import Scene, scene_of


def _dist2(rects: np.ndarray, pose: WorldPose) -> np.ndarray:
    ddx = np.maximum(np.maximum(rects[:, 0] - pose.x, pose.x - rects[:, 2]), 0.0)
    ddz = np.maximum(np.maximum(rects[:, 1] - pose.z, pose.z - rects[:, 3]), 0.0)
    return ddx * ddx + ddz * ddz


def _object_boxes_oracle(scene: Scene, pose: WorldPose, params: ConditionParams) -> tuple:
    parts, facing = scene.parts, scene.part_facing
    corner_x, corner_z = parts[:, [0, 0, 2, 2]], parts[:, [1, 3, 1, 3]]
    centre = scene.centres[scene.part_object]
    always = (facing[:, 0] == 0) & (facing[:, 1] == 0)
    near = (_dist2(scene.rects, pose) <= params.draw_distance**2)[scene.part_object]
    side = (pose.x - centre[:, 0]) * facing[:, 0] + (pose.z - centre[:, 1]) * facing[:, 1]
    fx, fz = unit(pose.heading)
    rx, rz = right_of(pose.heading)
    cx, cz = corner_x - pose.x, corner_z - pose.z
    fwd, lat = cx * fx + cz * fz, cx * rx + cz * rz
    out_of_view = (fwd <= NEAR).all(axis=1) | (lat > fwd).all(axis=1) | (lat < -fwd).all(axis=1)
    sel = np.flatnonzero(near & (always | (side > facing[:, 2])) & ~out_of_view)
    fwd, lat = fwd[sel], lat[sel]
    f0, f1 = np.maximum(fwd.min(axis=1), NEAR), fwd.max(axis=1)
    l0, l1 = lat.min(axis=1), lat.max(axis=1)
    u0, u1 = np.minimum(l0 / f0, l0 / f1), np.maximum(l1 / f0, l1 / f1)
    lo = np.clip(np.floor(u0 * FOCAL + (FOCAL - 0.5)) - 1, 0, SIZE).astype(np.int64)
    hi = np.clip(np.ceil(u1 * FOCAL + (FOCAL - 0.5)) + 2, 0, SIZE).astype(np.int64)
    wide = hi > lo
    sel, lo, hi = sel[wide], lo[wide], hi[wide]
    group = _dist2(scene.rects[scene.support[scene.part_object]][sel], pose)
    order = np.lexsort((-_dist2(parts[sel, :4], pose), parts[sel, 4], -group))
    sel, lo, hi = sel[order], lo[order], hi[order]
    p = parts[sel]
    extra = np.where(p[:, 5] < EYE, 1, np.where(p[:, 4] > EYE, 2, 0))
    rel = p[:, :4] - (pose.x, pose.z, pose.x, pose.z)
    return rel, FOCAL * (p[:, 4:6] - EYE), lo, hi, scene.part_label[sel], extra


@settings(max_examples=150)
@given(
    st.integers(0, 40),
    st.floats(-0.05, 1.05),
    st.floats(-0.05, 1.05),
    st.one_of(st.sampled_from([0.0, 90.0, 180.0, 270.0]), st.floats(0, 359.9)),
    st.sampled_from(CONDITIONS),
)
def test_object_boxes_are_the_numpy_oracle_bit_for_bit(
    seed: int, fx: float, fz: float, heading: float, condition: str
) -> None:
    layout = paper_office() if seed == 0 else generate_layout(seed)
    pose = WorldPose(round(fx * layout.width, 2), round(fz * layout.depth, 2), heading)
    scene, params = scene_of(layout), condition_params(condition)
    got = object_boxes(scene, pose, params)
    expected = _object_boxes_oracle(scene, pose, params)
    for a, b in zip(got, expected, strict=True):
        assert a.dtype == b.dtype and a.shape == b.shape
        assert a.tobytes() == b.tobytes()


def test_object_boxes_worked_example(two_rooms: Layout) -> None:
    """From (3, 6.5) in the Office facing south: the stool (in the Kitchen, off to the west,
    on the image's right), then the fridge (straight ahead, through the doorway), then the
    doorway's frame, farthest object first; facing north or west nothing is drawn."""
    scene, params = scene_of(two_rooms), condition_params("baseline")
    rel, _, lo, hi, _, _ = object_boxes(scene, WorldPose(3.0, 6.5, 180.0), params)
    eye = np.array([3.0, 6.5, 3.0, 6.5])
    part = [  # the box each row draws, found by its world planes
        np.flatnonzero(np.isclose(scene.parts[:, :4], r + eye).all(axis=1))[0] for r in rel
    ]
    objects = [two_rooms.objects[scene.part_object[p]].object_id for p in part]
    runs = [o for i, o in enumerate(objects) if i == 0 or objects[i - 1] != o]
    assert runs == ["Stool_1", "Fridge_1", "Doorway_1"]
    stool = np.array([o == "Stool_1" for o in objects])
    assert (lo[stool] > SIZE // 2).all() and (hi[stool] <= SIZE).all()
    fridge = np.array([o == "Fridge_1" for o in objects])
    assert lo[fridge].min() < SIZE // 2 < hi[fridge].max()  # its body spans the centre
    assert (rel[:, 1] < 0).all()  # every box lies south of the eye
    for heading in (0.0, 270.0):
        assert len(object_boxes(scene, WorldPose(3.0, 6.5, heading), params)[2]) == 0
