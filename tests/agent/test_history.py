"""The sliding window (system + last 10 turns) and single-image mode."""

from __future__ import annotations

import base64
import json

import pytest

from pytest_emrd.agent import HISTORY_TURNS, Conversation, UserTurn


def _turn(step: int, *, image: bool = True) -> UserTurn:
    if image:
        return UserTurn.with_frame(step, f"Step {step} of 50.", f"jpeg{step}".encode(), f"px{step}")
    return UserTurn(step, f"Step {step} of 50.")


def _run(conversation: Conversation, steps: int) -> list[dict]:
    """Play ``steps`` answered turns and return the request for the next one."""
    for step in range(1, steps + 1):
        conversation.request(_turn(step))
        conversation.record(_turn(step), f"reply {step}")
    return conversation.request(_turn(steps + 1))


def _texts(messages: list[dict]) -> list[str]:
    out = []
    for m in messages:
        content = m["content"]
        out.append(content if isinstance(content, str) else content[0]["text"])
    return out


def test_first_request_is_system_plus_current() -> None:
    messages = Conversation("SYS", single_image=False).request(_turn(1))
    assert [m["role"] for m in messages] == ["system", "user"]
    parts = messages[1]["content"]
    assert parts[0] == {"type": "text", "text": "Step 1 of 50."}
    expected = base64.b64encode(b"jpeg1").decode()
    assert parts[1]["image_url"]["url"] == f"data:image/jpeg;base64,{expected}"


@pytest.mark.parametrize("answered", [0, 1, 8, 9, 10, 11, 30])
def test_window_keeps_system_and_last_ten_turns(answered: int) -> None:
    messages = _run(Conversation("SYS", single_image=False), answered)
    kept = min(answered, HISTORY_TURNS - 1)
    assert len(messages) == 1 + 2 * kept + 1 <= 2 * HISTORY_TURNS
    assert messages[0] == {"role": "system", "content": "SYS"}
    assert [m["role"] for m in messages[1:]] == ["user", "assistant"] * kept + ["user"]
    first = answered - kept + 1
    assert _texts(messages[1:]) == [
        t for s in range(first, answered + 1) for t in (f"Step {s} of 50.", f"reply {s}")
    ] + [f"Step {answered + 1} of 50."]


def test_every_windowed_frame_is_an_image_in_multi_image_mode() -> None:
    conversation = Conversation("SYS", single_image=False)
    messages = _run(conversation, 4)
    images = [
        p
        for m in messages
        if isinstance(m["content"], list)
        for p in m["content"]
        if p["type"] == "image_url"
    ]
    assert len(images) == 5


def _reply(step: int, observation: str) -> str:
    body = {"observation": observation, "cognitive_map": {}, "action": "Turn(Right)"}
    return f"Sure.\n```json\n{json.dumps(body)}\n```"


def test_single_image_sends_only_the_newest_frame_and_summaries_of_the_others() -> None:
    conversation = Conversation("SYS", single_image=True)
    for step in range(1, 5):
        conversation.request(_turn(step))
        conversation.record(_turn(step), _reply(step, f"A desk,\n  a chair ({step})."))
    messages = conversation.request(_turn(5))
    users = [m for m in messages if m["role"] == "user"]
    assert all(isinstance(m["content"], str) for m in users[:-1])
    assert users[0]["content"] == (
        "Step 1 of 50.\nCamera frame of step 1, as you described it: A desk, a chair (1)."
    )
    assert [p["type"] for p in users[-1]["content"]] == ["text", "image_url"]
    images = [p for m in messages if isinstance(m["content"], list) for p in m["content"]]
    assert [p["type"] for p in images].count("image_url") == 1


@pytest.mark.parametrize("reply", ["not json at all", _reply(1, ""), _reply(1, "   ")])
def test_single_image_without_a_readable_observation_keeps_the_text_only(reply: str) -> None:
    conversation = Conversation("SYS", single_image=True)
    conversation.request(_turn(1))
    conversation.record(_turn(1), reply)
    assert conversation.request(_turn(2))[1] == {"role": "user", "content": "Step 1 of 50."}


def test_text_modality_sends_plain_strings() -> None:
    conversation = Conversation("SYS", single_image=False)
    conversation.record(_turn(1, image=False), "r1")
    messages = conversation.request(_turn(2, image=False))
    assert messages[1:] == [
        {"role": "user", "content": "Step 1 of 50."},
        {"role": "assistant", "content": "r1"},
        {"role": "user", "content": "Step 2 of 50."},
    ]
