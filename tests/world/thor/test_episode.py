"""A short scripted episode on the ai2thor backend (fake controller) that the metrics accept.

``pytest_emrd.episode.run_episode`` builds its simulator through ``world.make_simulator``,
which does not exist yet; this test drives the same loop by hand so the trajectory
contract is exercised end to end: spawn-frame poses, ground-truth visible ids, a perfect
cognitive map, a Term, JSON round trip, and ``episode_metrics``.
"""

from __future__ import annotations

import json

import pytest

from pytest_emrd.trajectory import (
    EpisodeSpec,
    GroundTruth,
    GroundTruthObject,
    MapEntry,
    RoomOutline,
    Step,
    Trajectory,
)
from pytest_emrd.world._geometry import to_spawn_frame
from pytest_emrd.world._model import Layout
from pytest_emrd.world.thor import ThorSimulator

metrics = pytest.importorskip("pytest_emrd.metrics._episode")


def _policy(sim: ThorSimulator, t: int) -> str:
    """Sweep the Office until the doorway is in view, cross it, sweep, then Term."""
    if sim.current_room() == "Office":
        return "Goto(Doorway_1)" if "Doorway_1" in sim.visible_ids() else "Turn(Right)"
    return "Turn(Left)" if t < 8 else "Term(Conference Room)"


def _truth(sim: ThorSimulator, layout: Layout) -> GroundTruth:
    spawn = sim.spawn_pose
    objects = tuple(
        GroundTruthObject(
            o.object_id, o.object_type, o.room, o.category, *to_spawn_frame(spawn, o.x, o.z)
        )
        for o in layout.objects
    )
    rooms = tuple(
        RoomOutline(
            r.name,
            tuple(
                to_spawn_frame(spawn, x, z)
                for x, z in ((r.x0, r.z0), (r.x0, r.z1), (r.x1, r.z1), (r.x1, r.z0))
            ),
        )
        for r in layout.rooms
    )
    ids = tuple(sorted(o.object_id for o in layout.objects))
    return GroundTruth(objects, rooms, ids, "Office")


def test_scripted_episode_yields_a_trajectory_the_metrics_accept(
    fake_controller: type, layout: Layout
) -> None:
    sim = ThorSimulator(controller_factory=fake_controller)
    obs = sim.reset(layout, "baseline", "Office", 3)
    truth = _truth(sim, layout)
    where = {o.object_id: o for o in truth.objects}
    belief: dict[str, MapEntry] = {}
    steps = []
    for t in range(1, 12):
        action = _policy(sim, t)
        pose, room, visible = obs.pose, sim.current_room(), sim.visible_ids()
        for oid in visible:
            o = where[oid]
            belief[oid] = MapEntry(oid, o.object_type, o.x, o.z, o.room)
        after = sim.step(action)
        steps.append(
            Step(
                t,
                pose,
                room,
                visible,
                tuple(belief.values()),
                action,
                after.success,
                after.feedback,
            )
        )
        obs = after
        if obs.done:
            break
    sim.close()
    assert obs.done and obs.terminal_room == "Conference Room"
    assert all(s.success for s in steps)
    traj = Trajectory(
        spec=EpisodeSpec("scout", "baseline", "office", 0, backend="ai2thor"),
        protocol="ai2thor-test",
        ground_truth=truth,
        steps=tuple(steps),
        status="terminated",
        final_room="Conference Room",
        chosen_room="Conference Room",
        chosen_room_raw="Conference Room",
    )
    again = Trajectory.from_dict(json.loads(json.dumps(traj.to_dict())))
    assert again == traj
    assert "Conference Room" in traj.rooms_visited
    result = metrics.episode_metrics(again)
    assert not result.errored and result.steps == len(steps)
    assert result.aec is not None and result.aec > 0
    assert result.never_visited is False
