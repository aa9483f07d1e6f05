"""The paper's "agents cannot scan rooms from doorways", on the paper office.

A scripted agent sweeps four headings at the spawn of every episode of a room (20 per room,
every condition): the episodes' first poses are distinct, and at most 2 objects of other
rooms are ever reported visible during the sweeps of a room. From 1 m before any doorway,
facing it, at most 3 objects of the next room are visible.
"""

from __future__ import annotations

import pytest

from pytest_emrd.rooms import ROOM_NAMES, ROOM_SLUGS
from pytest_emrd.trajectory import CONDITIONS, EpisodeSpec
from pytest_emrd.world import BuiltinSimulator, WorldPose, condition_params, paper_office
from pytest_emrd.world._motion import spawn_pose
from pytest_emrd.world._scene import scene_of
from pytest_emrd.world._visibility import sight

EPISODES = 20


def _rooms_of() -> dict[str, set[str]]:
    office = paper_office()
    rooms = {o.object_id: {o.room} for o in office.objects}
    for d in office.doorways:
        rooms[d.object_id] = {d.room_a, d.room_b}
    return rooms


@pytest.mark.parametrize("condition", CONDITIONS)
@pytest.mark.parametrize("room", ROOM_NAMES)
def test_sweeps_at_the_20_spawns_of_a_room_see_at_most_2_objects_of_other_rooms(
    room: str, condition: str
) -> None:
    rooms_of = _rooms_of()
    office, params = paper_office(), condition_params(condition)
    scene = scene_of(office)
    firsts: set[WorldPose] = set()
    other: set[str] = set()
    for episode in range(EPISODES):
        seed = EpisodeSpec("scout", condition, ROOM_SLUGS[room], episode).seed
        first = spawn_pose(scene, office.room(room), seed)
        firsts.add(first)
        assert office.room_at(first.x, first.z) == room
        for turn in range(4):
            pose = WorldPose(first.x, first.z, (first.heading + 90 * turn) % 360)
            seen = sight(scene, pose, params.visibility_distance, params.draw_distance)
            other |= {v.object_id for v in seen.listing(scene) if room not in rooms_of[v.object_id]}
    assert len(firsts) == EPISODES
    assert len({(p.x, p.z) for p in firsts}) == EPISODES  # distinct positions, not only poses
    assert len(other) <= 2, sorted(other)


def _before_doorways() -> list[tuple[str, WorldPose, str]]:
    """(doorway, pose 1 m before it facing it, the room beyond) for both sides of each."""
    out = []
    for d in paper_office().doorways:
        for sign in (1.0, -1.0):
            if d.axis == "x":
                pose = WorldPose(d.x, d.z + sign, 180.0 if sign > 0 else 0.0)
            else:
                pose = WorldPose(d.x + sign, d.z, 270.0 if sign > 0 else 90.0)
            here = paper_office().room_at(pose.x, pose.z)
            beyond = ({d.room_a, d.room_b} - {here}).pop()
            out.append((d.object_id, pose, beyond))
    return out


@pytest.mark.parametrize("condition", CONDITIONS)
def test_from_1m_before_a_doorway_at_most_3_objects_of_the_next_room_are_visible(
    condition: str,
) -> None:
    rooms_of = _rooms_of()
    scene = scene_of(paper_office())
    params = condition_params(condition)
    for doorway, pose, beyond in _before_doorways():
        seen = sight(scene, pose, params.visibility_distance, params.draw_distance)
        ids = {v.object_id for v in seen.listing(scene)}
        assert doorway in ids
        here = paper_office().room_at(pose.x, pose.z)
        next_room = {i for i in ids if beyond in rooms_of[i] and here not in rooms_of[i]}
        assert len(next_room) <= 3, (doorway, sorted(next_room))


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
