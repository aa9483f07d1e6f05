"""The fake THOR holds the ai2thor 5.0.0 contract it claims (see ``conftest.py``), so a
backend that passes against it does what a real build accepts."""

from __future__ import annotations

import copy
from typing import Any

import ai2thor.server
import pytest

from pytest_emrd.world import Layout, WorldPose
from pytest_emrd.world.thor import build_house

from .conftest import AGENT_KEYS, AGENT_Y, EMPTY_START, EVENT_KEYS, OBJECT_KEYS


@pytest.fixture
def house(layout: Layout) -> dict[str, Any]:
    return build_house(layout, "baseline", 0, agent=WorldPose(2.0, 5.0, 0.0))


def _teleport(x: float, z: float, **extra: Any) -> dict[str, Any]:
    return {
        "action": "TeleportFull",
        "position": {"x": x, "y": AGENT_Y, "z": z},
        "rotation": {"x": 0.0, "y": 0.0, "z": 0.0},
        "horizon": 0,
        "standing": True,
        **extra,
    }


@pytest.mark.parametrize(
    ("action", "message"),
    [
        ({"action": "TeleportFull", "position": {"x": 2.0, "y": AGENT_Y, "z": 5.0},
          "rotation": {"x": 0, "y": 0, "z": 0}}, "missing arguments: horizon, standing"),
        (_teleport(2.0, 5.0, speed=1), "unexpected arguments: speed"),
        ({"action": "Fly"}, "Invalid action: Fly"),
    ],
    ids=["missing", "unexpected", "unknown-action"],
)  # fmt: skip
def test_dispatch_errors_raise_value_error_like_the_python_side(
    fake_controller: type, house: dict[str, Any], action: dict[str, Any], message: str
) -> None:
    controller = fake_controller(scene=house, gridSize=0.25)
    with pytest.raises(ValueError, match=message):
        controller.step(action)


def test_events_are_ai2thor_events_with_thor_s_keys(
    fake_controller: type, house: dict[str, Any]
) -> None:
    event = fake_controller(scene=house, width=64, height=48).last_event
    assert isinstance(event, ai2thor.server.Event) and event.frame.shape == (48, 64, 3)
    assert set(event.metadata.keys()) == EVENT_KEYS
    assert set(event.metadata["agent"]) == AGENT_KEYS
    assert all(set(o) == OBJECT_KEYS for o in event.metadata["objects"])


def test_unknown_asset_ids_are_skipped_silently(
    fake_controller: type, house: dict[str, Any]
) -> None:
    broken = copy.deepcopy(house)
    broken["objects"][0]["assetId"] = "Coffee_Machine_1"
    event = fake_controller(scene=broken).last_event
    ids = {o["objectId"] for o in event.metadata["objects"]}
    assert event.metadata["lastActionSuccess"] and broken["objects"][0]["id"] not in ids
    assert len(ids) == len(house["objects"]) - 1 + len(house["doors"])


def test_the_agent_enters_only_through_agent_poses(
    fake_controller: type, house: dict[str, Any]
) -> None:
    old_style = copy.deepcopy(house)
    del old_style["metadata"]["agentPoses"]
    controller = fake_controller(scene=old_style)
    assert controller.last_event.metadata["agent"]["position"] == EMPTY_START
    event = controller.step(action="GetReachablePositions")
    assert not event.metadata["lastActionSuccess"]
    assert "beyond the scene bounds" in event.metadata["errorMessage"]


def test_the_lattice_is_anchored_at_the_agent_and_teleports_need_the_grid(
    fake_controller: type, house: dict[str, Any]
) -> None:
    off_grid = copy.deepcopy(house)
    off_grid["metadata"]["agentPoses"]["default"]["position"].update(x=2.1, z=5.1)
    controller = fake_controller(scene=off_grid, gridSize=0.25)
    points = controller.step(action="GetReachablePositions").metadata["actionReturn"]
    assert points and all(round((p["x"] - 2.1) / 0.25, 6) % 1 == 0 for p in points)
    event = controller.step(_teleport(points[1]["x"], points[1]["z"]))
    assert "is not on the grid of size 0.25" in event.metadata["errorMessage"]


@pytest.mark.parametrize(
    ("teleport", "message"),
    [
        ({**_teleport(2.0, 5.0), "rotation": {"x": 10.0, "y": 0.0, "z": 0.0}}, "pitch or roll"),
        (_teleport(2.0, 5.0, horizon=75), "horizon must be in [-30:60]"),
        (_teleport(40.0, 5.0), "out of scene bounds"),
        (_teleport(2.0, 5.0, position={"x": 2.0, "y": 0.5, "z": 5.0}), "too large a change"),
    ],
    ids=["pitch", "horizon", "bounds", "height"],
)
def test_teleport_full_checks_as_teleport_full_does(
    fake_controller: type, house: dict[str, Any], teleport: dict[str, Any], message: str
) -> None:
    controller = fake_controller(scene=house)
    event = controller.step(teleport)
    assert not event.metadata["lastActionSuccess"] and message in event.metadata["errorMessage"]
