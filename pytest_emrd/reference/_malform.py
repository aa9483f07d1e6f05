"""How a ``mimic`` reply is written out: pretty JSON, sometimes malformed the way VLMs do it.

A reply is rendered as indented JSON whose first key, ``state``, carries the agent's own
state on one line. Then, per reply, the caller draws one of: clean; one :data:`REPAIRABLE`
slip that :func:`pytest_emrd.agent.parse_reply` repairs and names (a code fence, prose around
it, a comment after the action line, a trailing comma); or :data:`FAILING` damage the parser
does not guess at (cut off inside the object, no comma after the ``observation`` value, a
bare ``...`` for elided map entries). None touches the ``state`` line, so the agent reads its
own state back from any of its replies (:func:`read_state`), as a model reads its own answer.
"""

from __future__ import annotations

import json
from typing import Any, Final

from pytest_emrd.errors import ProtocolError
from pytest_emrd.reference._phrasing import COMMENTS, PROSE, pick

REPAIRABLE: Final[tuple[str, ...]] = ("fence", "prose", "comment", "trailing_comma")
FAILING: Final[tuple[str, ...]] = ("truncated", "missing_comma", "ellipsis")
_STATE_LEAD: Final = '"state": '


def render(state: dict[str, Any], body: dict[str, Any]) -> str:
    """Indented JSON of ``body`` with ``state`` as its first key, on one line."""
    rest = json.dumps(body, indent=2, ensure_ascii=False)
    compact = json.dumps(state, separators=(",", ":"), sort_keys=True)
    return "{\n  " + _STATE_LEAD + compact + ",\n" + rest[2:]


def _line_end(text: str, key: str) -> int:
    """Index of the newline ending the top-level line of ``key``."""
    start = text.index(f'\n  "{key}": ')
    return text.index("\n", start + 1)


def malform(text: str, kind: str, u: float) -> str:
    """``text`` (from :func:`render`) with the slip or damage ``kind``; ``u`` picks wording."""
    if kind == "fence":
        return f"```json\n{text}\n```"
    if kind == "prose":
        before, after = pick(PROSE, u)
        return "\n".join(part for part in (before, text, after) if part)
    if kind == "comment":
        end = _line_end(text, "action")
        return f"{text[:end]} {pick(COMMENTS, u)}{text[end:]}"
    if kind == "trailing_comma":
        return text[: text.rindex("\n}")] + ",\n}"
    if kind == "truncated":
        start = text.index("\n", text.index(_STATE_LEAD)) + 1
        return text[: start + int((0.2 + 0.7 * u) * (len(text) - 2 - start))]
    if kind == "missing_comma":
        end = _line_end(text, "observation")
        return text[: end - 1] + text[end:]
    if kind == "ellipsis":  # inside the map when it has entries, else after the observation
        end = _line_end(text, "cognitive_map")
        if text[end - 1] != "{":
            end = _line_end(text, "observation")
        return f"{text[:end]}\n    ...{text[end:]}"
    raise ValueError(f"unknown malformation {kind!r}")


def read_state(text: str) -> dict[str, Any]:
    """The ``state`` object of one of the agent's own replies, however it was malformed.

    :param text: One of the agent's replies.
    :returns: The state the agent carried in it.
    """
    at = text.find(_STATE_LEAD)
    try:
        state = json.JSONDecoder().raw_decode(text, at + len(_STATE_LEAD))[0] if at >= 0 else None
    except (ValueError, IndexError) as exc:
        raise ProtocolError(f"previous assistant message carries no mimic state: {exc}") from exc
    if not isinstance(state, dict):
        raise ProtocolError("previous assistant message carries no mimic state.")
    return state
