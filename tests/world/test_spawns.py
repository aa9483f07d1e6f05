"""The paper's "20 runs for each starting room": distinct spawn points on the paper office.
What the sweeps and doorway views show: ``test_legibility.py``."""

from __future__ import annotations

import pytest

from pytest_emrd.rooms import ROOM_NAMES, ROOM_SLUGS
from pytest_emrd.trajectory import EpisodeSpec
from pytest_emrd.world import BuiltinSimulator, paper_office
from pytest_emrd.world._motion import spawn_pose
from pytest_emrd.world._scene import scene_of

EPISODES = 20


@pytest.mark.parametrize("room", ROOM_NAMES)
def test_the_20_episodes_of_a_room_start_on_distinct_points(room: str) -> None:
    office = paper_office()
    scene = scene_of(office)
    firsts = set()
    for episode in range(EPISODES):
        seed = EpisodeSpec("scout", "baseline", ROOM_SLUGS[room], episode).seed
        first = spawn_pose(scene, office.room(room), seed)
        assert office.room_at(first.x, first.z) == room
        firsts.add((first.x, first.z))
    assert len(firsts) == EPISODES


@pytest.mark.parametrize("room", ["Office", "Entrance", "Conference Room"])
def test_the_simulator_starts_the_20_episodes_of_a_room_on_the_spawn_poses(room: str) -> None:
    sim = BuiltinSimulator()
    scene = scene_of(paper_office())
    firsts = []
    for episode in range(EPISODES):
        seed = EpisodeSpec("scout", "baseline", ROOM_SLUGS[room], episode).seed
        sim.reset(paper_office(), "baseline", room, seed)
        assert sim.spawn_pose == spawn_pose(scene, paper_office().room(room), seed)
        firsts.append(sim.agent_pose)
    sim.close()
    assert len(set(firsts)) == EPISODES
