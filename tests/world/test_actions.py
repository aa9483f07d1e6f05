"""Invalid actions are consumed and explained; the grammar is forgiving about spelling."""

from __future__ import annotations

import pytest

from pytest_emrd.world import Layout

BAD = [
    ("", "could not read ''"),
    ("walk forward", "could not read 'walk forward'"),
    ("Fly(Kitchen)", "could not read"),
    ("Goto(Desk_1", "could not read"),
    ("Goto()", "Goto needs a target"),
    ("Goto(Sofa)", "no visible object matches 'Sofa'. Visible: "),
    ("Goto(Chair_999)", "no visible object matches 'Chair_999'"),
    ("Turn(Up)", "cannot turn 'Up'"),
]


@pytest.mark.parametrize(("action", "reason"), BAD, ids=[a or "empty" for a, _ in BAD])
def test_invalid_action_consumes_the_step_and_says_why(
    office: Layout, new_sim, action: str, reason: str
) -> None:
    sim = new_sim()
    start = sim.reset(office, "baseline", "office", 3)
    obs = sim.step(action)
    assert not obs.success and not obs.done and obs.step == 1
    assert reason in obs.feedback
    assert obs.feedback.endswith("Pose: x=0.00 z=0.00 heading=0.")
    assert obs.pose == start.pose and obs.frame_digest == start.frame_digest


def test_failed_goto_lists_what_is_visible(office: Layout, new_sim) -> None:
    sim = new_sim()
    start = sim.reset(office, "baseline", "office", 3)
    listed = ", ".join(v.object_id for v in start.visible)
    assert f"Visible: {listed}." in sim.step("Goto(Sofa)").feedback


@pytest.mark.parametrize(
    ("action", "room"),
    [("Term(kitchen)", "Kitchen"), ("Term(Garage)", None), ("Term()", None)],
    ids=["room", "other", "empty"],
)
def test_term_always_ends_the_episode(office: Layout, new_sim, action: str, room) -> None:
    """The paper: a trajectory concludes when the policy emits Term(r), whatever r names."""
    sim = new_sim()
    sim.reset(office, "baseline", "office", 3)
    obs = sim.step(action)
    assert obs.done and obs.success and obs.terminal_room == room
    assert "the episode is over" in obs.feedback
    assert not any(name in obs.feedback for name in ("Office", "Conference Room", "Entrance"))
    after = sim.step("Turn(Left)")
    assert after.done and not after.success and "the episode is over" in after.feedback


def _ids(layout: Layout) -> list[str]:
    return [o.object_id for o in layout.objects]


@pytest.mark.parametrize(
    "action", ["Goto(Sofa)", "Goto()", "Goto(Chair_999)", "Goto(Doorway)", "Goto(Desk_7)"]
)
def test_vision_feedback_names_no_object_id(office: Layout, new_sim, action: str) -> None:
    sim = new_sim()
    sim.reset(office, "baseline", "office", 3, symbolic=False)
    echoed = action[5:-1]  # the model's own text may come back; nothing else may name an id
    for step in ("Turn(Right)", action, "Turn(Left)", action):
        feedback = sim.step(step).feedback.replace(echoed, "")
        assert not [i for i in _ids(office) if i in feedback], feedback


def test_vision_goto_takes_types_and_ignores_instance_suffixes(office: Layout, new_sim) -> None:
    """Under vision Goto(Desk_9) is Goto(Desk): the nearest visible desk, whatever its id."""
    by_id, by_type = new_sim(), new_sim()
    start = by_id.reset(office, "baseline", "office", 3, symbolic=False)
    by_type.reset(office, "baseline", "office", 3, symbolic=False)
    seen = sorted(start.visible, key=lambda v: (v.distance, v.object_id))
    target = seen[-1]  # the farthest visible object: its id would pick it, its type does not
    nearest = next(v for v in seen if v.object_type == target.object_type)
    moved = by_id.step(f"Goto({target.object_id})")
    assert moved.pose == by_type.step(f"Goto({target.object_type})").pose
    symbolic = new_sim()
    symbolic.reset(office, "baseline", "office", 3)
    assert symbolic.step(f"Goto({nearest.object_id})").pose == moved.pose


@pytest.mark.parametrize(
    "spelling",
    ["turn(right)", "TURN ( RIGHT )", "Turn('Right')", ' Turn("right"). ', "Turn(\tRight\n)"],
)
def test_grammar_is_case_and_whitespace_tolerant(office: Layout, new_sim, spelling) -> None:
    sim = new_sim()
    sim.reset(office, "baseline", "office", 3)
    obs = sim.step(spelling)
    assert obs.success and obs.pose.heading == 90
