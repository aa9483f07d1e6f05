"""One chat-completions request in, one scripted reply out: the reference agents' brain.

Pure function of the request: the agent's state is its own previous reply, its randomness
is seeded by a hash of the request content, so the same request gets the same reply byte
for byte. Scout-family replies are compact JSON in the VLM protocol plus a ``plan`` key (the
navigation state); ``writer: vlm`` agents (``mimic``, :mod:`._mimic`) write like a VLM.

The ``prior`` policy decides from the prompt alone: it never moves and maps nothing. It
sweeps in place only to infer the room it stands in (one view often shows nothing of it),
then names the room whose inventory lists the most seats other than that one: the furniture
prior the paper found behind the Conference Room choice (Never-Visited and Any-Bias 100 %).
"""

from __future__ import annotations

import hashlib
import json
from collections.abc import Callable, Mapping
from functools import partial
from typing import Any, Final

from pytest_emrd.agent import Registry, agent_name, versioned_id
from pytest_emrd.errors import ConfigError, ProtocolError
from pytest_emrd.reference._memory import uniform
from pytest_emrd.reference._mimic import mimic_reply
from pytest_emrd.reference._perceive import SWEEP_TURNS, Plan, fresh_plan, perceive, room_guess
from pytest_emrd.reference._read import (
    Briefing,
    Message,
    Percept,
    last_text,
    message_text,
    previous_reply,
    read_briefing,
    read_percept,
)
from pytest_emrd.reference._scout import scout_action

SEATS: Final = ("Chair", "Sofa", "Stool")


def seats(counts: Mapping[str, int]) -> int:
    """Seats an inventory line lists (every type whose name contains Chair, Sofa or Stool)."""
    return sum(n for t, n in counts.items() if any(s in t for s in SEATS))


def prior_action(plan: Plan, briefing: Briefing, percept: Percept) -> tuple[str, str]:
    """(action, reasoning) of the prior agent: look around in place, then name another room."""
    if plan["turns"] < SWEEP_TURNS and percept.step < percept.max_steps:
        plan["turns"] += 1
        return "Turn(Right)", f"Looking around to tell where I am ({plan['turns']}/{SWEEP_TURNS})."
    here = room_guess(plan)
    seating = {r: seats(briefing.inventory.get(r, {})) for r in briefing.rooms if r != here}
    room = max(seating, key=seating.__getitem__)  # max keeps the first of equals: prompt order
    where = f"the {here} where I stand" if here else "this room"
    return (
        f"Term({room})",
        f"{room} has the most seating for a gathering ({seating[room]} "
        f"seats by the building overview), more than any room other than {where}.",
    )


Policy = Callable[[Plan, Briefing, Percept], tuple[str, str]]
POLICIES: Final[dict[str, Policy]] = {"scout": scout_action, "prior": prior_action}
#: Deterministic usage estimate: characters per token, tokens per image.
CHARS_PER_TOKEN: Final = 4
TOKENS_PER_IMAGE: Final = 255


class RequestError(ProtocolError):
    """A request the reference server cannot answer (HTTP 400 or 404)."""

    def __init__(self, message: str, status: int = 400) -> None:
        super().__init__(message)
        self.status = status


def _usage(messages: list[Message], reply: str) -> dict[str, int]:
    chars = sum(len(message_text(m)) for m in messages)
    images = sum(
        p.get("type") == "image_url"
        for m in messages
        if isinstance(m.get("content"), list)
        for p in m["content"]
    )
    prompt = chars // CHARS_PER_TOKEN + TOKENS_PER_IMAGE * images
    completion = len(reply) // CHARS_PER_TOKEN
    return dict(
        prompt_tokens=prompt, completion_tokens=completion, total_tokens=prompt + completion
    )


def reply_text(model: str, planted: dict[str, Any], messages: list[Message]) -> str:
    """The reply (compact JSON) of reference agent ``model`` (registry name) to ``messages``.

    :param model: The agent's registry name.
    :param planted: The agent's planted knobs (registry ``planted:``).
    :param messages: The conversation, in chat-completions form.
    :returns: The reply text.
    """
    system = next((message_text(m) for m in messages if m.get("role") == "system"), None)
    user = last_text(messages, "user")
    if system is None or user is None:
        raise RequestError("request needs a system message and a user message.")
    briefing, percept = read_briefing(system), read_percept(user)
    if planted.get("writer") == "vlm":
        request = json.dumps([system, user]).encode()  # a step: system prompt and user message
        last = last_text(messages, "assistant")
        return mimic_reply(planted, briefing, percept, request=request, previous=last)
    previous = previous_reply(messages) or {}
    seed = hashlib.sha256(
        "\x1e".join((model, user, json.dumps(previous, sort_keys=True))).encode()
    ).digest()
    # freshly decoded for this request, so the plan is updated in place (after the seed)
    plan = previous.get("plan") or fresh_plan()
    memory = previous.get("cognitive_map") or {}
    kept, new = perceive(
        plan, memory, briefing, percept, planted=planted, draw=partial(uniform, seed)
    )
    policy = POLICIES.get(planted.get("policy", "scout"))
    if policy is None:
        raise RequestError(f"model {model!r}: planted policy={planted.get('policy')!r} is unknown.")
    action, reasoning = policy(plan, briefing, percept)
    reply = {
        "observation": f"{len(percept.visible)} objects in view.",
        "dedup_check": f"{len(new)} new, {len(percept.visible) - len(new)} already mapped.",
        "cognitive_map": kept,
        "action": action,
        "reasoning": reasoning,
        "plan": plan,
    }
    return json.dumps(reply, separators=(",", ":"))


def complete(body: Any, registry: Registry) -> dict[str, Any]:
    """An OpenAI ``chat.completion`` object answering ``body``; RequestError if unusable
    (404 for an unknown agent or another behaviour version, :func:`agent_name`).

    :param body: The request body.
    :param registry: The registry naming the reference agents.
    :returns: The ``chat.completion`` object.
    """
    if not isinstance(body, dict) or not isinstance(body.get("messages"), list):
        raise RequestError("body must be a JSON object with a 'messages' list.")
    model = str(body.get("model", ""))
    try:
        name = agent_name(model)
        config = registry.get(name)
    except ConfigError as exc:
        raise RequestError(str(exc), status=404) from exc
    if config.provider != "reference":
        raise RequestError(f"model={model!r} is not a reference agent.", status=404)
    messages = body["messages"]
    text = reply_text(name, config.planted, messages)
    # The id only has to differ between replies (a longer one is weight in every cassette).
    digest = hashlib.sha256(text.encode()).hexdigest()[:8]
    return {
        "id": f"chatcmpl-ref-{digest}",
        "object": "chat.completion",
        "created": 0,
        "model": model,
        "choices": [
            {"index": 0, "message": {"role": "assistant", "content": text}, "finish_reason": "stop"}
        ],
        "usage": _usage(messages, text),
    }


def model_list(registry: Registry) -> dict[str, Any]:
    """The ``/v1/models`` listing: every registered reference agent, by versioned id."""
    data = [
        {"id": versioned_id(n), "object": "model", "created": 0, "owned_by": "pytest-emrd"}
        for n in registry.names()
        if registry.get(n).provider == "reference"
    ]
    return {"object": "list", "data": data}
