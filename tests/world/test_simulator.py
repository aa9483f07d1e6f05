"""The built-in simulator: determinism, observation contents, turns, termination."""

from __future__ import annotations

import hashlib
import io

import numpy as np
import pytest
from PIL import Image

from pytest_emrd.errors import ConfigError
from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.world import (
    BuiltinSimulator,
    Layout,
    WorldPose,
    _jpeg,
    _simulator,
    make_simulator,
)
from pytest_emrd.world._simulator import JPEG_QUALITY

SCRIPT = ("Turn(Right)", "Turn(Right)", "Goto(Doorway_2)", "Turn(Left)", "Turn(Around)")


def _run(sim: BuiltinSimulator, layout: Layout, condition: str = "baseline", seed: int = 3):
    return [sim.reset(layout, condition, "office", seed), *(sim.step(a) for a in SCRIPT)]


def test_same_seed_gives_identical_frames_and_digests(office: Layout, new_sim) -> None:
    a, b = _run(new_sim(), office), _run(new_sim(), office)
    for x, y in zip(a, b, strict=True):
        assert x.frame_digest == y.frame_digest
        assert np.array_equal(x.frame, y.frame)
        assert x.jpeg == y.jpeg
        assert (x.feedback, x.visible, x.pose) == (y.feedback, y.visible, y.pose)


def test_observation_carries_frame_digest_and_jpeg(office: Layout, new_sim) -> None:
    obs = new_sim().reset(office, "baseline", "office", 3)
    assert obs.frame.shape == (512, 512, 3) and obs.frame.dtype == np.uint8
    assert obs.frame_digest == hashlib.sha256(obs.frame.tobytes()).hexdigest()
    image = Image.open(io.BytesIO(obs.jpeg))
    assert (image.format, image.size, image.mode) == ("JPEG", (512, 512), "RGB")
    assert obs.step == 0 and obs.success and not obs.done and obs.terminal_room is None
    assert obs.feedback == "Episode started. Pose: x=0.00 z=0.00 heading=0."


def test_the_jpeg_is_encoded_on_first_read_only_and_once(
    office: Layout, new_sim, monkeypatch: pytest.MonkeyPatch
) -> None:
    """A replay never reads a frame's JPEG, so stepping must not encode one; a recording
    reads it (and a revisited pose's cached frame) without encoding it twice."""
    encoded: list[np.ndarray] = []
    encode = _jpeg.encode_jpeg

    def counting(frame: np.ndarray, quality: int) -> bytes:
        encoded.append(frame)
        return encode(frame, quality)

    monkeypatch.setattr(_jpeg, "encode_jpeg", counting)
    sim = new_sim()
    observations = [*_run(sim, office), sim.step("Turn(Around)")]  # back to a cached frame
    assert encoded == []
    jpegs = [obs.jpeg for obs in observations] + [obs.jpeg for obs in observations]
    rendered = {obs.frame_digest for obs in observations}
    assert len(encoded) == len(rendered) < len(observations)
    for obs, jpeg in zip(observations * 2, jpegs, strict=True):
        expected = io.BytesIO()
        Image.fromarray(obs.frame).save(expected, format="JPEG", quality=JPEG_QUALITY)
        assert jpeg == expected.getvalue()


def test_reset_places_the_agent_in_the_spawn_room_by_slug_or_name(office: Layout, new_sim) -> None:
    sim = new_sim()
    for room in ROOM_NAMES:
        sim.reset(office, "baseline", room, 11)
        assert sim.current_room() == room
    sim.reset(office, "baseline", "kitchen", 11)
    assert sim.current_room() == "Kitchen"
    assert sim.spawn_pose == sim.agent_pose and sim.spawn_pose.heading in (0, 90, 180, 270)


@pytest.mark.parametrize(
    ("action", "heading"), [("Turn(Right)", 90), ("Turn(Left)", 270), ("Turn(Around)", 180)]
)
def test_turns_rotate_in_place(office: Layout, new_sim, action: str, heading: int) -> None:
    sim = new_sim()
    sim.reset(office, "baseline", "office", 3)
    start = sim.agent_pose
    obs = sim.step(action)
    assert obs.success and obs.pose.heading == heading and (obs.pose.x, obs.pose.z) == (0, 0)
    assert (sim.agent_pose.x, sim.agent_pose.z) == (start.x, start.z)
    assert obs.feedback == f"{action} succeeded. Pose: x=0.00 z=0.00 heading={heading}."


def test_term_ends_the_episode_and_later_steps_fail(office: Layout, new_sim) -> None:
    sim = new_sim()
    sim.reset(office, "baseline", "office", 3)
    obs = sim.step("  term( conference room ) ")
    assert obs.success and obs.done and obs.terminal_room == "Conference Room"
    after = sim.step("Turn(Left)")
    assert not after.success and after.done and after.step == 2
    assert "the episode is over" in after.feedback and after.pose.heading == 0


def test_room_aliases_are_accepted_by_term(office: Layout, new_sim) -> None:
    sim = new_sim(room_aliases={"Room A": "Office"})
    sim.reset(office, "baseline", "office", 3)
    assert sim.step("Term(room a)").terminal_room == "Office"
    with pytest.raises(ConfigError, match="Atrium"):
        BuiltinSimulator(room_aliases={"Room B": "Atrium"})


def test_feedback_never_names_a_room(office: Layout, new_sim) -> None:
    for obs in _run(new_sim(), office):
        assert not any(room in obs.feedback for room in ROOM_NAMES), obs.feedback


def test_visible_objects_are_sorted_in_view_and_in_range(office: Layout, new_sim) -> None:
    for obs in _run(new_sim(), office):
        ids = [v.object_id for v in obs.visible]
        assert ids == sorted(ids)
        assert all(-45 <= v.bearing <= 45 and 0 < v.distance < 8.5 for v in obs.visible)


@pytest.mark.parametrize(
    ("condition", "spawn", "problem"),
    [("foggy", "office", "condition='foggy'"), ("baseline", "attic", "spawn_room='attic'")],
    ids=["unknown-condition", "unknown-spawn"],
)
def test_reset_rejects_bad_configuration(office: Layout, condition, spawn, problem) -> None:
    with pytest.raises(ConfigError, match=problem):
        make_simulator().reset(office, condition, spawn, 1)


def test_using_the_simulator_before_reset_is_a_config_error() -> None:
    with pytest.raises(ConfigError, match="reset"):
        make_simulator().step("Turn(Left)")


@pytest.mark.parametrize(
    ("options", "problem"),
    [
        ({"jpeg_quality": 0}, "jpeg_quality=0 must lie in"),
        ({"frame_cache": -1}, "frame_cache=-1 must be a whole number >= 0"),
        ({"frame_cache": 2.5}, "frame_cache=2.5"),
        ({"room_aliases": {"Room A": "Lobby"}}, "'Lobby' is not one of"),
    ],
    ids=["jpeg-quality-zero", "negative-cache", "fractional-cache", "alias-to-unknown-room"],
)
def test_bad_simulator_options_are_config_errors(options: dict, problem: str) -> None:
    with pytest.raises(ConfigError, match=problem):
        BuiltinSimulator(**options)


def test_a_full_sweep_returns_the_same_frame_with_or_without_the_cache(
    office: Layout, new_sim
) -> None:
    for sim in (new_sim(), new_sim(frame_cache=0)):
        start = sim.reset(office, "baseline", "office", 3)
        for _ in range(3):
            sim.step("Turn(Right)")
        back = sim.step("Turn(Right)")
        assert back.frame_digest == start.frame_digest and back.jpeg == start.jpeg
        assert not back.frame.flags.writeable


def test_a_view_seen_before_in_the_process_is_not_drawn_again_unless_read(
    office: Layout, new_sim, monkeypatch: pytest.MonkeyPatch
) -> None:
    """Episodes of one office and condition share views: a second run of the same script
    knows every digest without drawing; reading a frame draws it, the same pixels;
    ``frame_cache=0`` draws every view."""
    first = _run(new_sim(), office, seed=91)
    drawn: list[WorldPose] = []
    draw = _simulator.render

    def counting(scene, pose, params, table):  # type: ignore[no-untyped-def]
        drawn.append(pose)
        return draw(scene, pose, params, table)

    monkeypatch.setattr(_simulator, "render", counting)
    again = _run(new_sim(), office, seed=91)
    assert drawn == []
    assert [o.frame_digest for o in again] == [o.frame_digest for o in first]
    for obs, before in zip(again, first, strict=True):
        assert np.array_equal(obs.frame, before.frame) and obs.jpeg == before.jpeg
    assert 0 < len(drawn) <= len(again)
    drawn.clear()
    uncached = _run(make_simulator("builtin", frame_cache=0), office, seed=91)
    assert len(drawn) == len(uncached)
    assert [o.frame_digest for o in uncached] == [o.frame_digest for o in first]
