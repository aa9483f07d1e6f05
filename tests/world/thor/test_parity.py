"""The ai2thor backend speaks and starts like the builtin one: same grammar, same feedback
text, same spawn pose (snapped to THOR's grid)."""

from __future__ import annotations

import math
from collections.abc import Iterator

import pytest

from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.world import BuiltinSimulator, generate_layout
from pytest_emrd.world.thor import ThorSimulator
from pytest_emrd.world.thor._simulator import grid, nearest_in_room

SCRIPT = [
    "Turn(Right)",
    "turn( around ).",
    "Turn(Up)",
    "Goto()",
    "I will go to the desk",
    "Jump(Desk_1)",
    "Term(Garage)",
    "TURN(left)",
    "Term(kitchen)",
    "Turn(Left)",
]
"""Actions whose feedback does not depend on what is in view."""


@pytest.fixture
def thor(fake_controller: type) -> Iterator[ThorSimulator]:
    simulator = ThorSimulator(controller_factory=fake_controller)
    yield simulator
    simulator.close()


@pytest.mark.parametrize("seed", [0, 5])
def test_feedback_text_is_the_builtin_text(thor: ThorSimulator, seed: int) -> None:
    layout = generate_layout(seed)
    builtin = BuiltinSimulator()
    ours, theirs = (s.reset(layout, "baseline", "office", seed) for s in (thor, builtin))
    assert ours.feedback == theirs.feedback == "Episode started. Pose: x=0.00 z=0.00 heading=0."
    for action in SCRIPT:
        ours, theirs = thor.step(action), builtin.step(action)
        assert (ours.feedback, ours.success, ours.done, ours.pose) == (
            theirs.feedback,
            theirs.success,
            theirs.done,
            theirs.pose,
        )
        assert ours.terminal_room == theirs.terminal_room


@pytest.mark.parametrize("seed", [0, 1, 2, 3])
@pytest.mark.parametrize("room", ROOM_NAMES)
def test_spawn_is_the_builtin_spawn_snapped_to_the_thor_grid(
    thor: ThorSimulator, fake_controller: type, seed: int, room: str
) -> None:
    layout = generate_layout(seed)
    builtin = BuiltinSimulator()
    builtin.reset(layout, "baseline", room, seed)
    thor.reset(layout, "baseline", room, seed)
    want, got = builtin.spawn_pose, thor.spawn_pose
    reachable = grid({"x": x, "z": z} for x, z in fake_controller.instances[-1].reachable)
    assert (got.x, got.z) == nearest_in_room(reachable, want.x, want.z, layout.room(room))
    assert got.heading == want.heading
    assert math.hypot(got.x - want.x, got.z - want.z) <= 0.25 * math.sqrt(2) / 2 + 1e-9
    assert thor.current_room() == room
