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
    ("Term(Garage)", "'Garage' is not a room of this building"),
    ("Term()", "'' is not a room"),
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
    "spelling",
    ["turn(right)", "TURN ( RIGHT )", "Turn('Right')", ' Turn("right"). ', "Turn(\tRight\n)"],
)
def test_grammar_is_case_and_whitespace_tolerant(office: Layout, new_sim, spelling) -> None:
    sim = new_sim()
    sim.reset(office, "baseline", "office", 3)
    obs = sim.step(spelling)
    assert obs.success and obs.pose.heading == 90
