"""Episodes on the ai2thor backend through the real loop, the fake in place of THOR.

``run_episode`` picks the backend with ``world.make_simulator(spec.backend)``; with
``thor_installed`` that runs ai2thor's own start-up path (import, pre-flight, build lookup)
and constructs the fake as ``ai2thor.controller.Controller``. The scout reference agent
answers over the local HTTP endpoint, reading the symbolic list (``modality="both"``).
"""

from __future__ import annotations

import json
import time

import pytest

from pytest_emrd.episode import run_episode
from pytest_emrd.errors import ConfigError
from pytest_emrd.metrics import episode_metrics
from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.trajectory import EpisodeSpec, Trajectory
from pytest_emrd.world import discoverable_ids, episode_world, generate_layout, make_simulator
from pytest_emrd.world.thor import ThorSimulator


def test_make_simulator_builds_thor_with_the_given_options(fake_controller: type) -> None:
    sim = make_simulator("ai2thor", controller_factory=fake_controller, gpu_device=1)
    assert isinstance(sim, ThorSimulator)
    layout = generate_layout(4)
    sim.reset(layout, "low_light", "entrance", 4)
    (controller,) = fake_controller.instances
    assert controller.init["gpu_device"] == 1 and controller.init["scene"] is sim.house
    assert sim.current_room() == "Entrance"
    sim.close()
    assert controller.stopped


@pytest.mark.parametrize(
    ("spawn", "episode"), [("office", 1), ("entrance", 0)], ids=["office-ep01", "entrance-ep00"]
)
@pytest.mark.usefixtures("thor_installed")
def test_scout_episode_on_thor_yields_a_trajectory_the_metrics_accept(
    spawn: str, episode: int
) -> None:
    spec = EpisodeSpec("scout", "baseline", spawn, episode, modality="both", backend="ai2thor")
    traj = run_episode(spec)
    assert traj.status == "terminated", traj.error
    assert traj.chosen_room in ROOM_NAMES and traj.rationale
    assert all(s.success and s.parse_error is None for s in traj.steps)
    assert len(traj.rooms_visited) >= 3
    assert traj.ground_truth.discoverable_ids == discoverable_ids(episode_world(spec).layout)
    assert traj.steps[0].pose.x == traj.steps[0].pose.z == 0.0  # the spawn frame's origin
    again = Trajectory.from_dict(json.loads(json.dumps(traj.to_dict())))
    assert again == traj
    result = episode_metrics(again)
    assert not result.errored and result.steps == len(traj.steps)
    assert result.aec is not None and result.aec > 0.5
    assert result.never_visited is False


@pytest.mark.usefixtures("isolated_home", "vulkan")
def test_without_a_build_run_episode_fails_at_once_naming_the_fix() -> None:
    """A missing build is misconfiguration: it raises before the first step, never hangs."""
    spec = EpisodeSpec("scout", "baseline", "kitchen", 0, modality="both", backend="ai2thor")
    started = time.monotonic()
    with pytest.raises(ConfigError, match="no AI2-THOR build") as info:
        run_episode(spec)
    assert time.monotonic() - started < 10.0
    assert "local_executable_path" in str(info.value)
