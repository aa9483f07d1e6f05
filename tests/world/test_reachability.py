"""Every room is reachable from every spawn by Goto through doorways."""

from __future__ import annotations

import pytest

from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.world import Layout, WorldPose, condition_params, generate_layout, paper_office
from pytest_emrd.world._motion import approach, spawn_pose, through
from pytest_emrd.world._render import render, shade_table
from pytest_emrd.world._scene import scene_of
from pytest_emrd.world._visibility import in_view


def _reachable_rooms(layout: Layout, spawn: str, condition: str, doorways_only: bool) -> set[str]:
    """Rooms the agent can stand in, exploring every Turn and every visible Goto target."""
    scene = scene_of(layout)
    params = condition_params(condition)
    table = shade_table(scene.colors, params, scene.owners)
    start = spawn_pose(scene, layout.room(spawn), 0)
    seen, frontier = {start}, [start]
    while frontier:
        pose = frontier.pop()
        room = layout.room_at(pose.x, pose.z) or ""
        nexts = [WorldPose(pose.x, pose.z, (pose.heading + d) % 360) for d in (90, 180, 270)]
        for shown in in_view(scene, pose, render(scene, pose, params, table)[1]):
            i = scene.index[shown.object_id]
            obj = layout.objects[i]
            if obj.object_type == "Doorway":
                door = next(d for d in layout.doorways if d.object_id == obj.object_id)
                nexts.append(through(scene, door, pose, room))
            elif not doorways_only:
                nexts.append(approach(scene, int(i), pose))
        for nxt in nexts:
            if nxt is not None and nxt not in seen:
                seen.add(nxt)
                frontier.append(nxt)
    return {layout.room_at(p.x, p.z) for p in seen}


@pytest.mark.parametrize("seed", range(12))
def test_every_room_reachable_through_doorways_under_baseline(seed: int) -> None:
    layout = generate_layout(seed)
    for spawn in ROOM_NAMES:
        assert _reachable_rooms(layout, spawn, "baseline", True) == set(ROOM_NAMES), spawn


@pytest.mark.parametrize("spawn", ROOM_NAMES)
def test_low_light_keeps_every_room_of_the_paper_office_reachable(spawn: str) -> None:
    """In low light (objects legible to 3.25 m at most, doorways to 7 m) an agent that walks
    from object to object still finds every doorway of the paper's office (low light costs
    time and coverage, never a room)."""
    assert _reachable_rooms(paper_office(), spawn, "low_light", False) == set(ROOM_NAMES)


def test_a_walk_through_the_simulator_visits_all_rooms(office: Layout, new_sim) -> None:
    sim = new_sim()
    obs = sim.reset(office, "baseline", "entrance", 2)
    visited = [sim.current_room()]
    for _ in range(40):
        fresh = [
            d.object_id
            for d in office.doorways
            if d.object_id in {v.object_id for v in obs.visible}
            and ({d.room_a, d.room_b} - set(visited))
        ]
        obs = sim.step(f"Goto({fresh[0]})" if fresh else "Turn(Right)")
        if sim.current_room() not in visited:
            visited.append(sim.current_room())
        if len(visited) == len(ROOM_NAMES):
            break
    assert sorted(visited) == sorted(ROOM_NAMES)
