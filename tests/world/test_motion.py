"""Semantic motion: Goto stands in front of its target; doorways lead into the next room."""

from __future__ import annotations

import math

import pytest

from pytest_emrd.world import BuiltinSimulator, Layout, WorldPose, footprint, paper_office
from pytest_emrd.world._geometry import unit

TURNS = ("", "Turn(Right)", "Turn(Around)", "Turn(Left)")


def _facing(
    sim: BuiltinSimulator, turn: str, layout: Layout, spawn: str, seed: int = 5
) -> list[str]:
    obs = sim.reset(layout, "baseline", spawn, seed)
    if turn:
        obs = sim.step(turn)
    return [v.object_id for v in obs.visible]


def _rect_distance(pose: WorldPose, rect: tuple[float, float, float, float]) -> float:
    x0, z0, x1, z1 = rect
    return math.hypot(max(x0 - pose.x, 0, pose.x - x1), max(z0 - pose.z, 0, pose.z - z1))


def _ahead(pose: WorldPose, rect: tuple[float, float, float, float]) -> bool:
    fx, fz = unit(pose.heading)
    corners = [(x, z) for x in rect[::2] for z in rect[1::2]]
    lats = [(x - pose.x) * fz - (z - pose.z) * fx for x, z in corners]
    fwds = [(x - pose.x) * fx + (z - pose.z) * fz for x, z in corners]
    return any(f > 0 and abs(la) <= f for la, f in zip(lats, fwds, strict=True))


@pytest.mark.parametrize("turn", TURNS, ids=["ahead", "right", "behind", "left"])
def test_goto_object_stands_in_front_of_it_in_its_room(office: Layout, new_sim, turn) -> None:
    sim = new_sim()
    objects = {o.object_id: o for o in office.objects}
    seed, targets = next(
        (seed, found)
        for seed in range(40)
        if (
            found := [
                i
                for i in _facing(sim, turn, office, "office", seed)
                if objects[i].object_type != "Doorway"
            ]
        )
    )
    for target in targets:
        _facing(sim, turn, office, "office", seed)
        obs = sim.step(f"Goto({target})")
        assert obs.success, obs.feedback
        obj = objects[target]
        base = obj
        if obj.elevation > 0:  # an item on a desk or counter: stand at the furniture
            base = next(
                o
                for o in office.objects
                if o.elevation == 0
                and o.room == obj.room
                and o.height == obj.elevation
                and footprint(o)[0] <= obj.x <= footprint(o)[2]
                and footprint(o)[1] <= obj.z <= footprint(o)[3]
            )
        pose = sim.agent_pose
        assert sim.current_room() == obj.room
        assert 0.6 - 1e-9 <= _rect_distance(pose, footprint(base)) <= 0.85, target
        assert _ahead(pose, footprint(base)), target
        assert target in [v.object_id for v in obs.visible]


def test_goto_by_type_goes_to_the_nearest_visible_instance(office: Layout, new_sim) -> None:
    sim = new_sim()
    obs = sim.reset(office, "baseline", "office", 5)
    chosen = min(
        (v for v in obs.visible if v.object_type != "Doorway"),
        key=lambda v: v.distance,
    )
    same_type = [v for v in obs.visible if v.object_type == chosen.object_type]
    nearest = min(same_type, key=lambda v: (v.distance, v.object_id))
    after = sim.step(f"Goto({chosen.object_type.lower()})")
    assert after.success
    assert after.feedback.startswith(
        f"Goto({chosen.object_type.lower()}) succeeded: moved to {nearest.object_id}."
    )


def test_goto_doorway_passes_into_the_other_room(office: Layout, new_sim) -> None:
    sim = new_sim()
    for doorway in office.doorways:
        for start, other in ((doorway.room_a, doorway.room_b), (doorway.room_b, doorway.room_a)):
            for turn in TURNS:
                if doorway.object_id in _facing(sim, turn, office, start):
                    break
            else:
                pytest.fail(f"{doorway.object_id} not visible from the {start} spawn")
            obs = sim.step(f"Goto({doorway.object_id})")
            assert obs.success and sim.current_room() == other
            pose = sim.agent_pose
            assert math.hypot(pose.x - doorway.x, pose.z - doorway.z) == pytest.approx(1.0)
            fx, fz = unit(pose.heading)
            assert (doorway.x - pose.x) * fx + (doorway.z - pose.z) * fz < 0  # facing away


def test_a_doorway_seen_through_another_is_walked_up_to(new_sim) -> None:
    office = paper_office()  # such views from some spawn (seed 7's office has none)
    sim = new_sim()
    cases = 0
    for doorway in office.doorways:
        for spawn in {r.name for r in office.rooms} - {doorway.room_a, doorway.room_b}:
            seen = (
                (turn, seed)
                for seed in range(20)
                for turn in TURNS
                if doorway.object_id in _facing(sim, turn, office, spawn, seed)
            )
            if next(seen, None) is None:
                continue
            cases += 1
            assert sim.step(f"Goto({doorway.object_id})").success
            pose = sim.agent_pose
            assert sim.current_room() in (doorway.room_a, doorway.room_b)  # the room between
            assert math.hypot(pose.x - doorway.x, pose.z - doorway.z) == pytest.approx(1.0)
            fx, fz = unit(pose.heading)
            assert (doorway.x - pose.x) * fx + (doorway.z - pose.z) * fz == pytest.approx(1.0)
    assert cases >= 1
