"""Dead reckoning (the mimic's ``reckon`` knob): what an agent without the ``Pose:`` line keeps."""

from __future__ import annotations

import math

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd.episode import run_episode
from pytest_emrd.reference._odometry import (
    STAND_OFF_M,
    THROUGH_M,
    TURNS,
    aim,
    fresh_odometry,
    reckon,
)
from pytest_emrd.reference._read import Percept
from pytest_emrd.trajectory import EpisodeSpec, Pose
from pytest_emrd.world import VisibleObject

CLEAN = "mimic-spawn-s0-p0-h0-q0-r0-a0-b0"


ELSEWHERE = Pose(9.0, 9.0, 9.0)
"""The engine's pose in a percept: the reckoning must ignore it."""


def _percept(*visible: VisibleObject, confirmed: bool = True, pose: Pose = ELSEWHERE) -> Percept:
    return Percept(step=2, max_steps=50, pose=pose, visible=visible, confirmed=confirmed)


def _go(action: str, *seen: VisibleObject) -> Pose:
    """The pose reckoned after ``action``, sent from the origin with ``seen`` in view, succeeded."""
    odometry = fresh_odometry()
    aim(odometry, action, _percept(*seen, pose=Pose(0.0, 0.0, 0.0)))
    return reckon(odometry, _percept(), {}).pose


def test_a_confirmed_goto_ends_short_of_an_object_and_past_a_doorway() -> None:
    chair = VisibleObject("Chair_1", "Chair", 0.0, 3.0)
    assert _go("Goto(Chair_1)", chair) == Pose(0.0, 3.0 - STAND_OFF_M, 0.0)
    door = VisibleObject("Doorway_2", "Doorway", 80.0, 2.0)  # snapped to a quarter turn: 90
    after = _go("Goto(Doorway)", door)
    assert after.heading == 90.0
    door_x, door_z = 2.0 * math.sin(math.radians(80)), 2.0 * math.cos(math.radians(80))
    assert (after.x, after.z) == pytest.approx((door_x + THROUGH_M, door_z), abs=1e-4)


def test_what_the_feedback_does_not_confirm_does_not_move_it() -> None:
    odometry = fresh_odometry()
    aim(odometry, "Goto(Chair_1)", _percept(VisibleObject("Chair_1", "Chair", 0.0, 3.0)))
    assert reckon(odometry, _percept(confirmed=False), {}).pose == Pose(0.0, 0.0, 0.0)
    aim(odometry, "Goto(Sofa)", _percept())  # nothing of that type in view: no goal
    assert reckon(odometry, _percept(), {}).pose == Pose(0.0, 0.0, 0.0)


@given(st.lists(st.sampled_from(["Turn(Left)", "Turn(Right)", "Turn(Around)", "Term(X)"])))
def test_turns_only_turn(actions: list[str]) -> None:
    odometry, expected = fresh_odometry(), 0.0
    for action in actions:
        aim(odometry, action, _percept())
        pose = reckon(odometry, _percept(), {}).pose
        if action.startswith("Turn"):
            expected = (expected + TURNS[action[5:-1]]) % 360.0
        assert (pose.x, pose.z, pose.heading) == (0.0, 0.0, expected)


@given(
    st.sampled_from([0.0, 90.0, 180.0, 270.0]),
    st.floats(-5, 5),
    st.floats(-5, 5),
)
def test_re_sighting_placed_objects_finds_the_side_goto_ended_on(
    heading: float, x: float, z: float
) -> None:
    """The chair lies straight ahead, so the expected arrival faces north; the engine put the
    agent elsewhere, facing ``heading``: three objects it had placed, seen again, say where."""
    placed = {"Desk_1": (x + 1.0, z + 2.0), "Sofa_1": (x - 2.0, z + 0.5), "Plant_1": (x, z - 3.0)}
    seen = []
    for object_id, (ox, oz) in placed.items():
        bearing = (math.degrees(math.atan2(ox - x, oz - z)) - heading + 180.0) % 360.0 - 180.0
        seen.append(VisibleObject(object_id, object_id[:-2], bearing, math.dist((ox, oz), (x, z))))
    odometry = fresh_odometry()
    chair = VisibleObject("Chair_1", "Chair", 0.0, 3.0)
    aim(odometry, "Goto(Chair_1)", _percept(chair, pose=Pose(0.0, 0.0, 0.0)))
    memory = {k: {"x": ox, "z": oz} for k, (ox, oz) in placed.items()}
    pose = reckon(odometry, _percept(*seen), memory).pose
    assert pose.heading == heading
    assert (pose.x, pose.z) == pytest.approx((x, z), abs=1e-3)


def test_the_reckoning_mimic_walks_the_clean_path_and_maps_from_its_own_pose() -> None:
    def episode(model: str):
        return run_episode(EpisodeSpec(model, "baseline", "office", 0, modality="both"))

    engine, reckoned = episode(CLEAN), episode(f"{CLEAN}-reckon")
    assert [s.action for s in reckoned.steps] == [s.action for s in engine.steps]
    first_goto = next(i for i, s in enumerate(engine.steps) if s.action.startswith("Goto"))
    before = {e.label: (e.x, e.z) for e in engine.steps[first_goto].cognitive_map}
    assert before and before == {
        e.label: (e.x, e.z) for e in reckoned.steps[first_goto].cognitive_map
    }
    assert [(e.x, e.z) for e in reckoned.final_map] != [(e.x, e.z) for e in engine.final_map]
