"""The conversation a model is sent each step: a sliding window over the episode.

Appendix C: the system prompt plus the last :data:`HISTORY_TURNS` dialogue turns, the
current (unanswered) user message included. ``single_image`` mode (the paper's Claude
setting, "prior frames are converted to text-only summaries"): an earlier frame travels as
the model's own ``observation`` of that step (:data:`FRAME_SUMMARY`), the one summary that
adds no second model and nothing the model did not have.
"""

from __future__ import annotations

import base64
from collections import deque
from dataclasses import dataclass
from typing import Any, Final

from pytest_emrd import frames
from pytest_emrd.agent._parse import parse_reply

#: Dialogue turns in the window, the current (unanswered) one included.
HISTORY_TURNS: Final = 10
JPEG_DATA_URL: Final = "data:image/jpeg;base64,"
FRAME_SUMMARY: Final = "Camera frame of step {step}, as you described it: {observation}"


@dataclass(frozen=True)
class UserTurn:
    """One step's user message before it is rendered into the wire format."""

    step: int
    text: str
    image_url: str | None = None
    """The frame as requests carry it: a base64 JPEG data URL, or in a replay its pixel digest
    (``pixels:<sha256>``, what the cassette holds in the JPEG's place). None: no frame."""
    frame_digest: str | None = None

    @classmethod
    def with_frame(cls, step: int, text: str, jpeg: bytes, frame_digest: str) -> UserTurn:
        """The turn showing the frame ``jpeg`` (pixels ``frame_digest``) as a model sees it."""
        payload = base64.b64encode(jpeg).decode("ascii")
        return cls(step, text, f"{JPEG_DATA_URL}{payload}", frame_digest)

    @classmethod
    def replayed(cls, step: int, text: str, frame_digest: str) -> UserTurn:
        """The turn showing the frame with pixels ``frame_digest`` in a replay."""
        return cls(step, text, frames.by_digest(frame_digest), frame_digest)


def _user_message(turn: UserTurn) -> dict[str, Any]:
    if turn.image_url is None:
        return {"role": "user", "content": turn.text}
    frame = {"type": "image_url", "image_url": {"url": turn.image_url}}
    return {"role": "user", "content": [{"type": "text", "text": turn.text}, frame]}


class Conversation:
    """The episode's dialogue, rendered through the sliding window. Each message is built
    once and the same dict is sent again while it stays in the window (clients encode and
    redact each one once).

    :param system: The system prompt.
    :param single_image: Whether only the newest turn keeps its frame.
    """

    def __init__(self, system: str, *, single_image: bool) -> None:
        self.single_image = single_image
        self._system = {"role": "system", "content": system}
        self._answered: deque[tuple[dict[str, Any], dict[str, Any]]] = deque(
            maxlen=HISTORY_TURNS - 1
        )
        self._pending: tuple[UserTurn, dict[str, Any]] | None = None

    def request(self, current: UserTurn) -> list[dict[str, Any]]:
        """System prompt, the answered turns still in the window, then ``current``."""
        if self._pending is None or self._pending[0] is not current:
            self._pending = (current, _user_message(current))
        answered = (message for turn in self._answered for message in turn)
        return [self._system, *answered, self._pending[1]]

    def record(self, current: UserTurn, reply: str) -> None:
        """Append the answered turn; the oldest pair leaves the window first."""
        if self.single_image and current.image_url is not None:
            user = _summarised(current, reply)
        elif self._pending and self._pending[0] is current:
            user = self._pending[1]  # as sent: it keeps its frame (single-image mode: it had none)
        else:
            user = _user_message(current)
        self._pending = None
        self._answered.append((user, {"role": "assistant", "content": reply}))


def _summarised(turn: UserTurn, reply: str) -> dict[str, Any]:
    """``turn``'s message with its frame replaced by the summary (single-image mode)."""
    observation = " ".join(parse_reply(reply).observation.split())
    summary = FRAME_SUMMARY.format(step=turn.step, observation=observation)
    return {"role": "user", "content": f"{turn.text}\n{summary}" if observation else turn.text}
