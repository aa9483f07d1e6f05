"""The boxes the renderer paints, on a worked example: which objects, in which order, over
which columns. Their pixels: ``test_frame_identity.py``."""

from __future__ import annotations

import numpy as np

from pytest_emrd.world import Layout, WorldPose, condition_params
from pytest_emrd.world._render import SIZE, object_boxes
from pytest_emrd.world._scene import scene_of


def test_object_boxes_worked_example(two_rooms: Layout) -> None:
    """From (3, 6.5) in the Office facing south: the stool (in the Kitchen, off to the west,
    on the image's right), then the fridge (straight ahead, through the doorway), then the
    doorway's frame, farthest object first, the doorway's fog on the drawn distance; facing
    north or west nothing is drawn."""
    scene, params = scene_of(two_rooms), condition_params("baseline")
    rel, _, lo, hi, _, _, reach = object_boxes(scene, WorldPose(3.0, 6.5, 180.0), params)
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
    doorway = np.array([o == "Doorway_1" for o in objects])
    assert (reach[doorway] == params.draw_distance).all()
    assert (reach[~doorway] == params.visibility_distance).all()
    for heading in (0.0, 270.0):
        assert len(object_boxes(scene, WorldPose(3.0, 6.5, heading), params)[2]) == 0
