"""The episode loop with a scripted in-process client on the builtin world."""

from __future__ import annotations

import json

import pytest

from pytest_emrd import frames
from pytest_emrd.episode import protocol_version, run_episode, world_action
from pytest_emrd.errors import ConfigError
from pytest_emrd.metrics import episode_metrics
from pytest_emrd.trajectory import EpisodeSpec, MapEntry, Trajectory


def _spec(**overrides) -> EpisodeSpec:
    fields = {
        "model": "gemini",
        "condition": "baseline",
        "spawn": "kitchen",
        "episode": 0,
        "max_steps": 6,
    }
    fields.update(overrides)
    return EpisodeSpec(**fields)


def test_budget_episode_records_every_step(scripted, reply) -> None:
    client = scripted([reply("Turn(Right)", {"Fridge_1": {"type": "Fridge", "x": 1, "z": 2}})])
    traj = run_episode(_spec(), client=client)
    assert traj.status == "budget" and traj.error is None
    assert [s.index for s in traj.steps] == [1, 2, 3, 4, 5, 6]
    assert [s.pose.heading for s in traj.steps] == [0.0, 90.0, 180.0, 270.0, 0.0, 90.0]
    assert all(s.success and s.room == "Kitchen" for s in traj.steps)
    assert traj.final_map == (MapEntry("Fridge_1", "Fridge", 1.0, 2.0),)
    assert traj.protocol == protocol_version()
    assert traj.usage.prompt_tokens == 600
    assert not client.closed, "a client passed in stays open for its owner"
    assert Trajectory.from_dict(json.loads(json.dumps(traj.to_dict()))) == traj


def test_on_step_sees_every_step_as_it_completes(scripted, reply) -> None:
    seen: list[int] = []
    traj = run_episode(
        _spec(max_steps=3),
        client=scripted([reply("Turn(Left)")]),
        on_step=lambda step: seen.append(step.index),
    )
    assert seen == [s.index for s in traj.steps] == [1, 2, 3]


def test_parse_failure_keeps_previous_map_and_consumes_the_step(scripted, reply) -> None:
    first = reply("Turn(Left)", {"Sink_1": {"type": "Sink", "x": 0.5, "z": 1.5}})
    client = scripted([first, "I am not sure what to do.", reply("Turn(Left)", {})])
    traj = run_episode(_spec(max_steps=3), client=client)
    one, two, three = traj.steps
    assert two.parse_error == "no JSON object found in the reply"
    assert two.cognitive_map == one.cognitive_map != ()
    assert two.action == "" and not two.success
    assert two.raw_reply == "I am not sure what to do."
    assert three.cognitive_map == () and three.parse_error is None


def test_transport_failure_is_an_errored_trajectory_keeping_steps(scripted, reply) -> None:
    client = scripted([reply("Turn(Right)")], fail_at=3)
    traj = run_episode(_spec(), client=client)
    assert traj.status == "errored"
    assert traj.error is not None and traj.error.startswith("TransportError: POST")
    assert len(traj.steps) == 2


@pytest.mark.parametrize(
    ("variant", "said", "canonical"),
    [
        ("neutral", "Room A", "Conference Room"),
        ("default", "kitchen", "Kitchen"),
        ("neutral", "'Room D'", "Kitchen"),
    ],
    ids=["neutral-alias", "case", "quoted-alias"],
)
def test_term_resolves_aliases_before_the_world(scripted, reply, variant, said, canonical) -> None:
    client = scripted([reply("Turn(Right)"), reply(f"Term({said})", reasoning="big table")])
    traj = run_episode(_spec(variant=variant), client=client)
    assert traj.status == "terminated" and len(traj.steps) == 2
    assert (traj.chosen_room, traj.chosen_room_raw, traj.rationale) == (
        canonical,
        said.strip(),
        "big table",
    )
    assert traj.steps[-1].action == f"Term({said})"


def test_term_naming_another_room_ends_the_episode_as_other(scripted, reply) -> None:
    """The paper: a trajectory concludes when the policy emits Term(r); r outside the four
    rooms is the focal column X, kept verbatim."""
    client = scripted([reply("Term(Lobby)", reasoning="the lobby is safest"), reply("Turn(Left)")])
    traj = run_episode(_spec(max_steps=5), client=client)
    assert traj.status == "terminated" and len(traj.steps) == 1 and traj.steps[0].success
    assert traj.chosen_room is None and traj.chosen_room_raw == "Lobby"
    assert traj.rationale == "the lobby is safest"
    assert episode_metrics(traj).chosen_letter == "X"


@pytest.mark.parametrize("modality", ["vision", "text", "both"])
def test_user_message_per_modality(scripted, reply, modality) -> None:
    client = scripted([reply("Turn(Right)")])
    run_episode(_spec(modality=modality, max_steps=2), client=client)
    user = client.requests[1][-1]
    parts = (
        user["content"]
        if isinstance(user["content"], list)
        else [{"type": "text", "text": user["content"]}]
    )
    text = parts[0]["text"]
    assert text.startswith("Step 2 of 2.\nEngine feedback: ")
    assert "Pose: x=" in text
    assert ("Visible objects" in text) == (modality != "vision")
    images = [p for p in parts if p["type"] == "image_url"]
    assert len(images) == (0 if modality == "text" else 1)
    for image in images:
        payload = image["image_url"]["url"].split(",", 1)[1]
        assert frames.pixel_digest_for(payload).startswith("pixels:")


def test_history_reaches_the_model(scripted, reply) -> None:
    client = scripted([reply("Turn(Right)")])
    run_episode(_spec(max_steps=12), client=client)
    assert [len(r) for r in client.requests] == [2, 4, 6, 8, 10, 12, 14, 16, 18, 20, 20, 20]
    assert client.requests[0][0]["role"] == "system"
    assert "Fridge" in client.requests[0][0]["content"]


def test_single_image_model_sends_one_frame(scripted, reply, monkeypatch) -> None:
    client = scripted([reply("Turn(Right)")])
    run_episode(_spec(model="claude", max_steps=4), client=client)
    images = [
        p
        for m in client.requests[-1]
        if isinstance(m["content"], list)
        for p in m["content"]
        if p["type"] == "image_url"
    ]
    assert len(images) == 1


@pytest.mark.parametrize(
    ("overrides", "match"),
    [
        ({"model": "gpt-4o"}, "not in the registry"),
        ({"condition": "fog"}, "condition='fog'"),
        ({"variant": "B9"}, "variant='B9'"),
        ({"modality": "audio"}, "modality='audio'"),
        ({"spawn": "garage"}, "spawn='garage'"),
        ({"max_steps": 0}, "max_steps=0"),
    ],
    ids=["model", "condition", "variant", "modality", "spawn", "max-steps"],
)
def test_bad_specs_raise_config_errors(scripted, reply, overrides, match) -> None:
    with pytest.raises(ConfigError, match=match):
        run_episode(_spec(**overrides), client=scripted([reply("Turn(Right)")]))


@pytest.mark.parametrize(
    ("action", "variant", "expected"),
    [
        ("Term(Room B)", "neutral", ("Term(Entrance)", "Room B")),
        ("term( conference room )", "B2", ("Term(Conference Room)", "conference room")),
        ("Term(Garage)", "default", ("Term(Garage)", "Garage")),
        ("Goto(Doorway_1)", "neutral", ("Goto(Doorway_1)", None)),
    ],
    ids=["alias", "spacing", "unknown", "not-term"],
)
def test_world_action(action, variant, expected) -> None:
    assert world_action(action, variant) == expected
