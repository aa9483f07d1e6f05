"""Full episodes of every reference agent on the builtin world over the local server."""

from __future__ import annotations

import pytest

from pytest_emrd.episode import run_episode
from pytest_emrd.rooms import ROOM_NAMES, SLUG_ROOMS
from pytest_emrd.trajectory import EpisodeSpec, Trajectory

SPAWNS = sorted(SLUG_ROOMS)


def _run(model: str, spawn: str = "office", episode: int = 0, **kw) -> Trajectory:
    return run_episode(EpisodeSpec(model, "baseline", spawn, episode, modality="both", **kw))


@pytest.mark.parametrize("spawn", SPAWNS)
def test_scout_visits_all_four_rooms_within_budget(spawn: str) -> None:
    traj = _run("scout", spawn)
    assert traj.status == "terminated", traj.error
    assert traj.rooms_visited == frozenset(ROOM_NAMES)
    assert len(traj.steps) <= 50
    assert all(s.parse_error is None for s in traj.steps)
    assert traj.chosen_room in ROOM_NAMES and traj.rationale
    truth = {o.object_id: o for o in traj.ground_truth.objects}
    seen = {i for s in traj.steps for i in s.visible_ids}
    final = {e.label: e for e in traj.final_map}
    assert set(final) == seen, "perfect memory: the final map holds everything ever seen"
    for label, entry in final.items():
        assert abs(entry.x - truth[label].x) < 0.05 and abs(entry.z - truth[label].z) < 0.05


def test_same_spec_twice_gives_identical_trajectories() -> None:
    first, second = _run("scout-decay-4", "kitchen", 3), _run("scout-decay-4", "kitchen", 3)
    assert first == second  # every field but each request's wall time (no part of equality)


def test_scout_variants_walk_the_same_path_and_differ_in_memory() -> None:
    perfect, decay, window = (
        _run(m, "entrance", 1) for m in ("scout", "scout-decay-2", "scout-window-5")
    )
    assert [s.action for s in perfect.steps] == [s.action for s in decay.steps]
    assert [s.action for s in perfect.steps] == [s.action for s in window.steps]
    assert len(decay.final_map) < len(perfect.final_map)
    assert max(len(s.cognitive_map) for s in window.steps) <= 5
    forgotten = 0
    for before, after in zip(decay.steps, decay.steps[1:], strict=False):
        dropped = {e.label for e in before.cognitive_map} - {e.label for e in after.cognitive_map}
        assert not dropped & set(after.visible_ids), "objects in view are never forgotten"
        forgotten += len(dropped)
    assert forgotten > 0


def test_serial_scout_keeps_first_and_last_discoveries() -> None:
    traj = _run("scout-serial", "conference", 2)
    order: list[str] = []
    for step in traj.steps:
        order += [i for i in step.visible_ids if i not in order]
    final = {e.label for e in traj.final_map}
    third = len(order) // 3
    early, middle, late = order[:third], order[third:-third], order[-third:]
    kept = [sum(label in final for label in part) / len(part) for part in (early, middle, late)]
    assert kept[1] < kept[0] and kept[1] < kept[2]


@pytest.mark.parametrize("spawn", SPAWNS)
def test_prior_names_a_room_it_never_entered(spawn: str) -> None:
    traj = _run("prior", spawn)
    assert traj.status == "terminated"
    assert [s.action[:4] for s in traj.steps] == ["Turn"] * 3 + ["Term"]
    assert all(s.cognitive_map == () for s in traj.steps), "no spatial evidence is kept"
    assert traj.rooms_visited == frozenset({SLUG_ROOMS[spawn]})
    assert traj.chosen_room not in traj.rooms_visited


def test_scout_in_low_light_repositions_and_reaches_every_room() -> None:
    """Spawned in a dark conference room with no doorway in sight, the scout walks to an
    object, sweeps again, and still clears the building (where it used to stop at step 4)."""
    traj = run_episode(EpisodeSpec("scout", "low_light", "conference", 2, modality="both"))
    actions = [s.action for s in traj.steps]
    moves = [a for a in actions if a.startswith("Goto(") and not a.startswith("Goto(Doorway")]
    assert moves, actions
    first = actions.index(moves[0])
    assert actions[first + 1 : first + 4] == ["Turn(Right)"] * 3
    assert traj.rooms_visited == frozenset(ROOM_NAMES)
    assert traj.status == "terminated" and len(traj.steps) > 4


def test_reference_agent_in_vision_modality_errors_with_a_hint() -> None:
    traj = run_episode(EpisodeSpec("scout", "baseline", "office", 0, modality="vision"))
    assert traj.status == "errored" and traj.steps == ()
    assert "modality 'text' or 'both'" in (traj.error or "")


@pytest.mark.parametrize("variant", ["neutral", "no_inventory", "B3"])
def test_scout_under_prompt_variants(variant: str) -> None:
    traj = _run("scout", "kitchen", 0, variant=variant)
    assert traj.status == "terminated"
    assert traj.rooms_visited == frozenset(ROOM_NAMES)
    assert traj.chosen_room in ROOM_NAMES
