"""The paper's "agents cannot scan rooms from doorways", through the episode loop: a scripted
model sweeps four headings and terminates, 20 episodes per spawn room."""

from __future__ import annotations

import pytest

from pytest_emrd.episode import run_episode
from pytest_emrd.rooms import SLUG_ROOMS
from pytest_emrd.trajectory import EpisodeSpec
from pytest_emrd.world import paper_office

SWEEP = ["Turn(Right)", "Turn(Right)", "Turn(Right)", "Term(Office)"]


@pytest.mark.parametrize("spawn", ["office", "entrance", "conference"])
def test_twenty_sweeps_start_apart_and_see_at_most_2_objects_of_other_rooms(
    scripted, reply, spawn: str
) -> None:
    office = paper_office()
    rooms_of = {o.object_id: {o.room} for o in office.objects}
    for d in office.doorways:
        rooms_of[d.object_id] = {d.room_a, d.room_b}
    room = SLUG_ROOMS[spawn]
    firsts, other = set(), set()
    for episode in range(20):
        client = scripted([reply(a) for a in SWEEP])
        spec = EpisodeSpec("gemini", "baseline", spawn, episode, modality="both")
        traj = run_episode(spec, client=client)
        assert traj.status == "terminated" and len(traj.steps) == len(SWEEP)
        # the first pose is the spawn frame's origin: two fixed objects in that frame tell it
        truth = {o.object_id: (o.x, o.z) for o in traj.ground_truth.objects}
        firsts.add((truth["Door_1"], truth["Doorway_1"]))
        assert {s.room for s in traj.steps} == {room}
        other |= {i for s in traj.steps for i in s.visible_ids if room not in rooms_of[i]}
    assert len(firsts) == 20
    assert len(other) <= 2, sorted(other)
