"""How a scripted agent reads its request: the system prompt, the ``text`` part of the
newest user message and its own previous reply, exactly what a VLM is sent and no more.
"""

from __future__ import annotations

import json
import math
import re
from dataclasses import dataclass
from typing import Any, Final

from pytest_emrd.agent import OVERVIEW_HEADING, VISIBLE_HEADING, read_profile
from pytest_emrd.errors import ProtocolError
from pytest_emrd.trajectory import Pose
from pytest_emrd.world import VisibleObject

_ROOMS_LINE = re.compile(r"^The building has four rooms: (?P<names>.+)\.$", re.MULTILINE)
_ROOM_LINE = re.compile(r"^- (?P<room>[^:]+): (?P<items>.*?)\.(?: .*)?$")
_STEP = re.compile(r"^Step (?P<k>\d+) of (?P<n>\d+)\.$", re.MULTILINE)
_POSE = re.compile(
    r"Pose: x=(?P<x>-?\d+(?:\.\d+)?) z=(?P<z>-?\d+(?:\.\d+)?) heading=(?P<h>-?\d+(?:\.\d+)?)\.?$",
    re.MULTILINE,
)
_CONFIRMED = re.compile(r"^Engine feedback: \S.*? succeeded", re.MULTILINE)
_VISIBLE = re.compile(
    r"^- (?P<id>\S+) \| (?P<type>\S+) \| (?P<b>-?\d+(?:\.\d+)?) \| (?P<d>\d+(?:\.\d+)?)$"
)
#: One chat-completions message (``role``, ``content``: a string or a list of parts).
Message = dict[str, Any]
NOT_SYMBOLIC: Final = (
    "reference agents act on the symbolic visible list; run them with modality 'text' or "
    "'both' (their registry default), not 'vision'."
)


@dataclass(frozen=True)
class Briefing:
    """What the system prompt tells the agent about the building."""

    rooms: tuple[str, ...]
    inventory: dict[str, dict[str, int]]
    """Room (as the prompt spells it) -> type -> count; empty under ``no_inventory``."""


@dataclass(frozen=True)
class Percept:
    """What the newest user message says."""

    step: int
    max_steps: int
    pose: Pose
    visible: tuple[VisibleObject, ...]
    confirmed: bool
    """The feedback says the last action succeeded."""


def along(x: float, z: float, heading: float, distance: float) -> tuple[float, float]:
    """The point ``distance`` m from ``(x, z)`` towards ``heading`` (degrees clockwise from +z)."""
    angle = math.radians(heading)
    return x + distance * math.sin(angle), z + distance * math.cos(angle)


def placed(percept: Percept, seen: VisibleObject) -> tuple[float, float]:
    """Where ``seen`` lies in the spawn frame, from the pose and its bearing and distance."""
    return along(percept.pose.x, percept.pose.z, percept.pose.heading + seen.bearing, seen.distance)


def read_briefing(system: str) -> Briefing:
    """Room names and inventory from the system prompt's building overview."""
    if OVERVIEW_HEADING not in system:
        raise ProtocolError("system prompt has no building overview; is this an EMRD request?")
    overview = system.partition(OVERVIEW_HEADING)[2].partition("\n\n")[0]
    names = _ROOMS_LINE.search(overview)
    if names is None:
        raise ProtocolError("building overview does not list the rooms.")
    rooms = tuple(n.strip() for n in names["names"].split(","))
    inventory = {
        m["room"]: read_profile(m["items"])
        for line in overview.splitlines()
        if (m := _ROOM_LINE.match(line))
    }
    return Briefing(rooms, inventory)


def read_percept(text: str) -> Percept:
    """Step counter, pose, visible list and confirmation from a user message's text part."""
    step, pose = _STEP.search(text), _POSE.search(text)
    if step is None or pose is None:
        raise ProtocolError("user message lacks the 'Step k of N.' line or the 'Pose:' feedback.")
    if VISIBLE_HEADING not in text:
        raise ProtocolError(NOT_SYMBOLIC)
    listing = text.partition(VISIBLE_HEADING)[2]
    visible = tuple(
        VisibleObject(m["id"], m["type"], float(m["b"]), float(m["d"]))
        for line in listing.splitlines()
        if (m := _VISIBLE.match(line))
    )
    at = Pose(float(pose["x"]), float(pose["z"]), float(pose["h"]))
    confirmed = _CONFIRMED.search(text) is not None
    return Percept(int(step["k"]), int(step["n"]), at, visible, confirmed)


def message_text(message: Message) -> str:
    """The text of an OpenAI-format message (string content or the text parts)."""
    content = message.get("content")
    if isinstance(content, str):
        return content
    if isinstance(content, list):
        return "\n".join(p.get("text", "") for p in content if p.get("type") == "text")
    raise ProtocolError(f"message content is {type(content).__name__}, not text or parts.")


def last_text(messages: list[Message], role: str) -> str | None:
    """The text of the newest message from ``role`` (the agent's own last reply for
    ``assistant``), or None when there is none (the first step)."""
    return next((message_text(m) for m in reversed(messages) if m.get("role") == role), None)


def previous_reply(messages: list[Message]) -> dict[str, Any] | None:
    """The agent's own last reply (decoded JSON), or None at the first step."""
    text = last_text(messages, "assistant")
    if text is None:
        return None
    try:
        data = json.loads(text)
    except ValueError as exc:
        raise ProtocolError(f"previous assistant message is not JSON: {exc}") from exc
    return data if isinstance(data, dict) else None
