"""ThorSimulator against the fake controller: THOR calls, actions, observations."""

from __future__ import annotations

import hashlib
import io
from collections.abc import Iterator
from typing import Any

import numpy as np
import pytest
from PIL import Image

from pytest_emrd.world import Layout, Observation, condition_params
from pytest_emrd.world.thor import ThorSimulator


@pytest.fixture
def sim(fake_controller: type) -> Iterator[ThorSimulator]:
    simulator = ThorSimulator(controller_factory=fake_controller)
    yield simulator
    simulator.close()


def _controller(fake_controller: type) -> Any:
    return fake_controller.instances[-1]


def _actions(fake_controller: type) -> list[str]:
    return [name for name, _ in _controller(fake_controller).calls]


def _face(sim: ThorSimulator, object_id: str) -> Observation:
    """Turn until ``object_id`` is in view (at most one full turn)."""
    for _ in range(4):
        obs = sim.step("Turn(Right)")
        if object_id in sim.visible_ids():
            return obs
    raise AssertionError(f"{object_id} never came into view")


@pytest.mark.parametrize("condition", ["baseline", "low_light", "texture"])
def test_reset_starts_thor_with_the_paper_settings(
    sim: ThorSimulator, fake_controller: type, layout: Layout, condition: str
) -> None:
    sim.reset(layout, condition, "Office", 3)
    init = _controller(fake_controller).init
    assert {k: init[k] for k in ("agentMode", "platform", "width", "height", "fieldOfView")} == {
        "agentMode": "default",
        "platform": "CloudRendering",
        "width": 512,
        "height": 512,
        "fieldOfView": 90,
    }
    assert init["snapToGrid"] is True and init["rotateStepDegrees"] == 90
    assert init["visibilityDistance"] == condition_params(condition).draw_distance
    assert init["scene"] is sim.house and init["scene"]["metadata"]["schema"] == "1.0.0"


@pytest.mark.parametrize(
    ("condition", "expected"),
    [
        ("baseline", ["GetReachablePositions", "TeleportFull"]),
        ("low_light", ["GetReachablePositions", "TeleportFull"]),
        (
            "texture",
            ["GetReachablePositions", "RandomizeMaterials", "RandomizeColors", "TeleportFull"],
        ),
    ],  # after the controller's own Initialize and CreateHouse
    ids=["baseline", "low_light", "texture"],
)
def test_conditions_issue_the_right_calls_at_reset(
    sim: ThorSimulator, fake_controller: type, layout: Layout, condition: str, expected: list[str]
) -> None:
    sim.reset(layout, condition, "Kitchen", 1)
    assert _actions(fake_controller) == ["Initialize", "CreateHouse", *expected]


def test_first_observation_is_a_usable_frame_at_the_spawn_origin(
    sim: ThorSimulator, layout: Layout
) -> None:
    obs = sim.reset(layout, "baseline", "Office", 3)
    assert (obs.step, obs.success, obs.done) == (0, True, False)
    assert (obs.pose.x, obs.pose.z, obs.pose.heading) == (0.0, 0.0, 0.0)
    assert obs.frame is not None and obs.frame.shape == (512, 512, 3)
    assert obs.frame.dtype == np.uint8
    assert obs.frame_digest == hashlib.sha256(obs.frame.tobytes()).hexdigest()
    assert Image.open(io.BytesIO(obs.jpeg)).size == (512, 512)
    assert sim.current_room() == "Office"
    assert "Office" not in obs.feedback and "Pose:" in obs.feedback


@pytest.mark.parametrize(
    ("action", "calls", "turned"),
    [
        ("Turn(Left)", [("RotateLeft", {"degrees": 90})], 270.0),
        ("Turn(Right)", [("RotateRight", {"degrees": 90})], 90.0),
        ("turn( around )", [("RotateRight", {"degrees": 90})] * 2, 180.0),
    ],
    ids=["left", "right", "around"],
)
def test_turns_map_to_thor_rotations(
    sim: ThorSimulator,
    fake_controller: type,
    layout: Layout,
    action: str,
    calls: list[tuple[str, dict[str, Any]]],
    turned: float,
) -> None:
    sim.reset(layout, "baseline", "Office", 3)
    before = len(_controller(fake_controller).calls)
    obs = sim.step(action)
    assert _controller(fake_controller).calls[before:] == calls
    assert obs.success and obs.pose.heading == turned and obs.step == 1


def test_goto_an_object_teleports_next_to_it_facing_it(
    sim: ThorSimulator, fake_controller: type, layout: Layout
) -> None:
    sim.reset(layout, "baseline", "Office", 3)
    _face(sim, "Desk_1")
    obs = sim.step("Goto(Desk)")
    name, args = _controller(fake_controller).calls[-1]
    assert obs.success and name == "TeleportFull"
    assert obs.feedback.startswith("Goto(Desk) succeeded: moved to Desk_1. Pose: x=")
    assert args["rotation"]["y"] % 90 == 0 and args["horizon"] == 0
    assert "Desk_1" in sim.visible_ids()
    desk = next(v for v in obs.visible if v.object_id == "Desk_1")
    assert desk.distance < 1.5 and abs(desk.bearing) <= 30


def test_goto_a_doorway_enters_the_next_room(sim: ThorSimulator, layout: Layout) -> None:
    sim.reset(layout, "baseline", "Office", 3)
    _face(sim, "Doorway_1")
    obs = sim.step("Goto(Doorway_1)")
    assert obs.success and sim.current_room() == "Conference Room"
    assert sim.agent_pose.heading == 90.0  # facing into the Conference Room, away from the gap


def test_a_doorway_seen_from_a_third_room_is_walked_up_to(
    sim: ThorSimulator, fake_controller: type, layout: Layout
) -> None:
    """From the Office, Doorway_3 (Kitchen-Entrance) shows through Doorway_2: Goto stops in
    the Kitchen facing it, never jumping over the Kitchen into the Entrance."""
    sim.reset(layout, "baseline", "Office", 3)
    _controller(fake_controller).step(
        action="TeleportFull",
        position={"x": 0.75, "y": 0.9009997, "z": 5.0},
        rotation={"x": 0.0, "y": 0.0, "z": 0.0},
        horizon=0,
        standing=True,
    )
    _face(sim, "Doorway_3")
    assert sim.current_room() == "Office"
    obs = sim.step("Goto(Doorway_3)")
    assert obs.success and sim.current_room() == "Kitchen"
    assert sim.agent_pose.heading == 90.0 and "Doorway_3" in sim.visible_ids()


@pytest.mark.parametrize(
    ("action", "reason"),
    [
        ("Goto(Fridge_1)", "no visible object matches 'Fridge_1'. Visible: "),
        ("Goto(Piano)", "no visible object matches 'Piano'"),
        ("Goto()", "Goto needs a target"),
        ("Jump(Desk_1)", "could not read 'Jump(Desk_1)'"),
        ("I will go to the desk", "could not read"),
        ("Turn(Up)", "cannot turn 'Up'"),
    ],
    ids=[
        "out-of-view",
        "unknown-target",
        "no-target",
        "unknown-verb",
        "prose",
        "bad-turn",
    ],
)
def test_invalid_actions_fail_the_step_without_moving(
    sim: ThorSimulator, fake_controller: type, layout: Layout, action: str, reason: str
) -> None:
    start = sim.reset(layout, "baseline", "Office", 3)
    before = len(_controller(fake_controller).calls)
    obs = sim.step(action)
    assert not obs.success and reason in obs.feedback and obs.step == 1
    assert _controller(fake_controller).calls[before:] == []
    assert obs.pose == start.pose and not obs.done


def test_term_ends_the_episode(sim: ThorSimulator, layout: Layout) -> None:
    sim.reset(layout, "baseline", "Office", 3)
    obs = sim.step("Term(Kitchen)")
    assert obs.success and obs.done and obs.terminal_room == "Kitchen"
    assert obs.feedback.startswith("Term(Kitchen) succeeded: the episode is over. Pose:")
    after = sim.step("Turn(Left)")
    assert not after.success and after.feedback.startswith(
        "Turn(Left) failed: the episode is over."
    )
    assert after.done and after.step == 2


def test_term_outside_the_four_rooms_ends_the_episode_as_other(
    sim: ThorSimulator, layout: Layout
) -> None:
    sim.reset(layout, "baseline", "Office", 3)
    obs = sim.step("Term(Garage)")
    assert obs.success and obs.done and obs.terminal_room is None
    assert "'Garage' is not one of the four rooms" in obs.feedback


def test_vision_feedback_on_thor_names_no_object_id(sim: ThorSimulator, layout: Layout) -> None:
    start = sim.reset(layout, "baseline", "Office", 3, symbolic=False)
    ids = [o.object_id for o in layout.objects]
    feedback = sim.step("Goto(Piano)").feedback
    assert start.visible and not [i for i in ids if i in feedback], feedback


def test_term_accepts_slugs_and_room_aliases(fake_controller: type, layout: Layout) -> None:
    sim = ThorSimulator(controller_factory=fake_controller, room_aliases={"Room A": "Office"})
    sim.reset(layout, "baseline", "kitchen", 3)
    assert sim.current_room() == "Kitchen"
    assert sim.step("Term(room a)").terminal_room == "Office"
    sim.close()


def test_a_move_thor_refuses_fails_the_step(
    sim: ThorSimulator, fake_controller: type, layout: Layout
) -> None:
    sim.reset(layout, "baseline", "Office", 3)
    _face(sim, "Desk_1")
    controller = _controller(fake_controller)
    controller._do_TeleportFull = lambda **_: (False, "Cannot teleport: collision.", None)
    obs = sim.step("Goto(Desk_1)")
    assert not obs.success and "AI2-THOR refused it (Cannot teleport: collision.)" in obs.feedback


def test_low_light_shortens_what_is_reported_visible(fake_controller: type, layout: Layout) -> None:
    seen = {}
    for condition in ("baseline", "low_light"):
        sim = ThorSimulator(controller_factory=fake_controller)
        sim.reset(layout, condition, "Conference Room", 4)
        far = [v for _ in range(4) for v in sim.step("Turn(Right)").visible]
        assert far
        seen[condition] = {v.object_id for v in far}
        sim.close()
    assert seen["low_light"] <= seen["baseline"]


def test_second_reset_reuses_the_controller(
    sim: ThorSimulator, fake_controller: type, layout: Layout
) -> None:
    sim.reset(layout, "baseline", "Office", 3)
    sim.reset(layout, "low_light", "Entrance", 4)
    assert len(fake_controller.instances) == 1
    args = next(a for name, a in _controller(fake_controller).calls if name == "reset")
    assert args == {"visibilityDistance": condition_params("low_light").draw_distance}
    assert sim.current_room() == "Entrance"


def test_close_stops_thor(fake_controller: type, layout: Layout) -> None:
    sim = ThorSimulator(controller_factory=fake_controller)
    sim.reset(layout, "baseline", "Office", 3)
    sim.close()
    sim.close()
    assert fake_controller.instances[-1].stopped
