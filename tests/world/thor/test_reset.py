"""Reset against the strict fake: the agent enters the house through ``agentPoses`` on
THOR's grid, and every THOR answer reset depends on is checked."""

from __future__ import annotations

from typing import Any

import pytest

from pytest_emrd.errors import ConfigError
from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.world import Layout, generate_layout, paper_office
from pytest_emrd.world.thor import ThorSimulator

SEEDS = range(12)


@pytest.mark.parametrize("offices", ["paper", "generated"])
def test_48_resets_and_a_first_step_succeed(fake_controller: type, offices: str) -> None:
    """12 seeds x 4 rooms: the spawn is inside the house, on the grid, and THOR takes it."""
    sim = ThorSimulator(controller_factory=fake_controller)
    failures = []
    for seed in SEEDS:
        layout = paper_office() if offices == "paper" else generate_layout(seed)
        for room in ROOM_NAMES:
            try:
                start = sim.reset(layout, "baseline", room, seed)
                step = sim.step("Turn(Right)")
            except ConfigError as exc:
                failures.append((seed, room, str(exc)))
                continue
            assert start.success and step.success and sim.current_room() == room
            assert sim.spawn_pose.x % 0.25 == 0 and sim.spawn_pose.z % 0.25 == 0
    sim.close()
    assert failures == []


def test_the_spawn_teleport_uses_the_height_thor_returned(
    fake_controller: type, layout: Layout
) -> None:
    """THOR refuses a ``TeleportFull`` whose ``y`` is off the floor height by > 0.05 m."""

    class TallerAgent(fake_controller):  # type: ignore[misc, valid-type]
        def __init__(self, **init: Any) -> None:
            super().__init__(**init)
            self.agent_y = 1.0

    sim = ThorSimulator(controller_factory=TallerAgent)
    sim.reset(layout, "baseline", "Office", 3)
    name, args = fake_controller.instances[-1].calls[-1]
    assert name == "TeleportFull" and args["position"]["y"] == 1.0


def _failing(base: type, action: str, message: str) -> type:
    def refuse(self: Any, **_: Any) -> tuple[bool, str, Any]:
        return False, message, None

    return type(f"Failing{action}", (base,), {f"_do_{action}": refuse})


@pytest.mark.parametrize(
    ("action", "condition", "message", "what"),
    [
        ("CreateHouse", "baseline", "Wall wall|1|0.00 not found", "CreateHouse of house"),
        ("RandomizeMaterials", "texture", "No materials for room type", "RandomizeMaterials"),
        ("RandomizeColors", "texture", "Colour randomisation failed", "RandomizeColors"),
        ("TeleportFull", "baseline", "Cannot teleport due to collision", "the spawn TeleportFull"),
    ],
    ids=["create-house", "randomize-materials", "randomize-colors", "first-teleport"],
)
def test_a_refused_reset_step_is_one_line_with_thors_message(
    fake_controller: type, layout: Layout, action: str, condition: str, message: str, what: str
) -> None:
    sim = ThorSimulator(controller_factory=_failing(fake_controller, action, message))
    with pytest.raises(ConfigError) as info:
        sim.reset(layout, condition, "Office", 3)
    text = str(info.value)
    assert f"AI2-THOR refused {what}" in text and message in text and "\n" not in text


def test_a_house_without_agent_poses_fails_with_thors_reason(
    fake_controller: type, layout: Layout
) -> None:
    """A build that leaves the agent where the empty scene put it (as with a house written
    to ``metadata.agent`` only) walks no lattice: the error says so, in THOR's words."""

    class IgnoresPoses(fake_controller):  # type: ignore[misc, valid-type]
        def _do_CreateHouse(self, house: dict[str, Any]) -> tuple[bool, str, Any]:
            stripped = {**house, "metadata": {**house["metadata"], "agentPoses": {}}}
            return super()._do_CreateHouse(stripped)

    sim = ThorSimulator(controller_factory=IgnoresPoses)
    with pytest.raises(ConfigError, match=r"GetReachablePositions: .*beyond the scene bounds"):
        sim.reset(layout, "baseline", "Office", 3)
