"""The paper's protocol, checked on what episodes actually send to a model.

Neutral: no real room name in any request (system prompt, feedback, errors, single-image
summaries). Vision: no object id the model could not read from a frame. Both are scanned on
every request of recorded episodes: the HTTP bodies a reference agent's cassette holds, and
the messages a scripted model is sent on the error paths.
"""

from __future__ import annotations

import json
import re
from typing import Any

import pytest

from pytest_emrd.agent import load_registry
from pytest_emrd.cassette import cassette_path, decode
from pytest_emrd.episode import protocol_version, run_episode
from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.trajectory import EpisodeSpec
from pytest_emrd.world import episode_world
from tests._episodes import agent_runner, run_with_cassette

ROOM_NAME = re.compile(r"\b(" + "|".join(re.escape(n) for n in ROOM_NAMES) + r")\b")
#: Actions that walk every error path a model can trigger (Term last: it ends the episode).
AWKWARD = [
    "Goto(Room A)",
    "Goto(Doorway_1)",
    "Goto(Desk_2)",
    "Goto(Sofa)",
    "Goto()",
    "Turn(Up)",
    "walk around",
    "Goto(Doorway)",
    "Goto(Door)",
    "Turn(Right)",
    "Goto(Chair)",
]


def _texts(messages: list[dict[str, Any]], roles: tuple[str, ...]) -> list[str]:
    out = []
    for m in messages:
        if m.get("role") not in roles:
            continue
        content = m["content"]
        parts = (
            [content] if isinstance(content, str) else [p["text"] for p in content if "text" in p]
        )
        out.extend(parts)
    return out


def _recorded_bodies(spec: EpisodeSpec, root) -> list[dict[str, Any]]:
    runner = agent_runner(load_registry())
    try:
        run = run_with_cassette(
            spec, runner, cassettes=root, protocol=protocol_version(), record_mode="all"
        )
    finally:
        runner.close()
    assert run.trajectory.status == "terminated", run.trajectory.error
    data = decode(cassette_path(root, spec).read_bytes())
    return [json.loads(r.body) for r in data.requests]


@pytest.mark.parametrize("spawn", ["conference", "kitchen"])
def test_no_request_of_a_neutral_scout_episode_names_a_room(tmp_path, spawn: str) -> None:
    spec = EpisodeSpec("scout", "baseline", spawn, 1, variant="neutral", modality="both")
    bodies = _recorded_bodies(spec, tmp_path)
    assert len(bodies) > 10
    for body in bodies:
        text = json.dumps(body, ensure_ascii=False)
        assert not ROOM_NAME.search(text), ROOM_NAME.search(text)


def test_no_message_of_a_neutral_single_image_episode_names_a_room(scripted, reply) -> None:
    """Error feedback and single-image summaries too (claude: single-image mode)."""
    assert load_registry().get("claude").single_image
    client = scripted([reply(a) for a in [*AWKWARD, "not json at all", "Term(Room Z)"]])
    spec = EpisodeSpec("claude", "low_light", "office", 0, variant="neutral", modality="both")
    traj = run_episode(spec, client=client)
    assert traj.status == "terminated" and traj.chosen_room is None
    assert not any("not re-sent" in t for r in client.requests for t in _texts(r, ("user",)))
    for request in client.requests:
        for text in _texts(request, ("system", "user")):
            assert not ROOM_NAME.search(text), text


@pytest.mark.parametrize("spawn", ["office", "entrance"])
def test_no_vision_request_carries_an_object_id(scripted, reply, spawn: str) -> None:
    """Under vision the model reads no id from a frame, so no text it is sent names one
    (its own action text may come back in the feedback; that is all)."""
    client = scripted([reply(a) for a in [*AWKWARD, "Term(Entrance)"]])
    spec = EpisodeSpec("gemini", "baseline", spawn, 3, modality="vision")
    traj = run_episode(spec, client=client)
    assert traj.status == "terminated" and len(client.requests) == len(AWKWARD) + 1
    assert any(s.success and s.action.startswith("Goto(") for s in traj.steps)
    ids = [o.object_id for o in episode_world(spec).layout.objects]
    named = re.compile(r"\b(" + "|".join(ids) + r")\b")
    for request in client.requests:
        for text in _texts(request, ("system", "user")):
            for action in AWKWARD:  # the model's own words, echoed
                text = text.replace(action, "").replace(repr(action[5:-1]), "")
            assert not named.search(text), named.search(text)


def test_symbolic_modalities_keep_the_ids(scripted, reply) -> None:
    client = scripted([reply("Turn(Right)")])
    spec = EpisodeSpec("gemini", "baseline", "office", 3, modality="both", max_steps=2)
    run_episode(spec, client=client)
    user = _texts(client.requests[-1], ("user",))[-1]
    assert re.search(r"^- [A-Za-z]+_\d+ \| ", user, re.MULTILINE)
    assert "Goto(Desk_2)" in _texts(client.requests[0], ("system",))[0]


def test_each_user_message_states_the_pose_once(scripted, reply) -> None:
    client = scripted([reply("Turn(Right)")])
    run_episode(EpisodeSpec("gemini", "baseline", "office", 0, max_steps=3), client=client)
    for request in client.requests:
        user = _texts(request, ("user",))[-1]
        assert user.count("Pose:") == 1 and user.count("heading=") == 1, user
