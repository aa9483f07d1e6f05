"""Explaining a replay that failed, each cause with the command that fixes it: drift (the
first differing field of a request the cassette does not hold), a modality mismatch, and
an unreadable recorded response (one the client asked for again: a retry)."""

from __future__ import annotations

import shlex
from pathlib import Path
from typing import Any, Final

from pytest_emrd._scrub import scrub
from pytest_emrd.agent._prompt import VISIBLE_HEADING
from pytest_emrd.cassette._redact import Redacted

_PREVIEW: Final = 80
_CONTEXT: Final = 40
_BODY_EXCERPT: Final = 160
_MISSING: Final = "<absent>"


def _preview(value: Any) -> str:
    text = repr(value)
    return text if len(text) <= _PREVIEW else text[: _PREVIEW - 3] + "..."


def first_difference(new: Any, recorded: Any, where: str = "body") -> tuple[str, Any, Any] | None:
    """``(path, new value, recorded value)`` of the first difference, depth first, or None.

    Dict keys are visited in sorted order (the canonical order), list items by index; a key
    or item present on one side only is reported with ``<absent>`` on the other.
    """
    if isinstance(new, dict) and isinstance(recorded, dict):
        for key in sorted(set(new) | set(recorded)):
            if key not in new or key not in recorded:
                return f"{where}.{key}", new.get(key, _MISSING), recorded.get(key, _MISSING)
            found = first_difference(new[key], recorded[key], f"{where}.{key}")
            if found:
                return found
        return None
    if isinstance(new, list) and isinstance(recorded, list):
        for i in range(max(len(new), len(recorded))):
            if i >= len(new) or i >= len(recorded):
                a = new[i] if i < len(new) else _MISSING
                b = recorded[i] if i < len(recorded) else _MISSING
                return f"{where}[{i}]", a, b
            found = first_difference(new[i], recorded[i], f"{where}[{i}]")
            if found:
                return found
        return None
    if new != recorded or type(new) is not type(recorded):
        return where, new, recorded
    return None


def text_context(now: str, then: str, width: int = _CONTEXT) -> str:
    """Where two texts first differ, with ``width`` characters of context on each side."""
    pairs = enumerate(zip(now, then, strict=False))
    at = next((i for i, (a, b) in pairs if a != b), min(len(now), len(then)))
    start = max(0, at - width)
    lead = "..." if start else ""

    def window(text: str) -> str:
        tail = "..." if len(text) > at + width else ""
        return repr(text[start : at + width]) + tail

    return (
        f"at character {at} (of {len(now)} now, {len(then)} recorded): "
        f"now {lead}{window(now)}, recorded {lead}{window(then)}"
    )


def request_modality(redacted: Redacted) -> str | None:
    """The modality a recorded request was made in: frames and a symbolic list (``both``),
    frames only (``vision``), the list only (``text``); ``None`` when the body is not JSON."""
    if not redacted.parsed:
        return None
    listed = VISIBLE_HEADING in redacted.body.decode(errors="replace")
    if redacted.images:
        return "both" if listed else "vision"
    return "text"


def drift_message(
    *,
    cassette: str,
    request_index: int,
    new_tree: Any,
    recorded_tree: Any | None,
    recorded: int,
    command: str = "",
) -> str:
    """The failure text of a request that matches nothing in the cassette."""
    head = (
        f"environment or prompt drift: request {request_index + 1} of the episode matches "
        f"nothing in cassette={cassette!r}"
    )
    fix = f" If the change is intended, re-record it: {command}" if command else ""
    if new_tree is None:
        return f"{head}; its body is not JSON, and a body that cannot be parsed never matches."
    if recorded_tree is None:
        return (
            f"{head}; the cassette holds only {recorded} request(s), so the episode now makes "
            f"more requests than when it was recorded (the world or the agent behaves "
            f"differently).{fix}"
        )
    found = first_difference(new_tree, recorded_tree)
    if found is None:
        return (
            f"{head}; the body equals recorded request {request_index + 1}, "
            f"which was already played.{fix}"
        )
    where, now, then = found
    if isinstance(now, str) and isinstance(then, str):
        detail = text_context(now, then)
    else:
        detail = f"now {_preview(now)}, recorded {_preview(then)}"
    return f"{head}; first differing field {where} {detail}.{fix}"


def modality_message(
    *, cassette: Path, recorded: str, asked: str, home: Path, record: str, rerecord: str
) -> str:
    """The failure text of a replay in another modality than the recording. ``home`` is where an
    episode in the ``recorded`` modality keeps its cassette: when it is free the fix moves the
    file there, then records the ``asked`` episode with ``record``; when it holds one, this
    file is a stray copy that ``rerecord`` replaces. No fix overwrites a ``recorded`` cassette."""
    head = (
        f"modality mismatch: cassette={str(cassette)!r} was recorded in modality {recorded!r} "
        f"and this run shows the model {asked!r}."
    )
    if home == cassette:  # no registry to tell the modalities' paths apart
        return (
            f"{head} Replay it with --emrd-modality={recorded}, or replace it by the {asked!r} "
            f"episode (the {recorded!r} recording is lost): {rerecord}"
        )
    if home.is_file():
        return (
            f"{head} The {recorded!r} episode has its own cassette, {home} (replay it with "
            f"--emrd-modality={recorded}); re-record this one in {asked!r}: {rerecord}"
        )
    folder = shlex.join(["mkdir", "-p", str(home.parent)])
    move = f"{folder} && {shlex.join(['mv', str(cassette), str(home)])}"
    return (
        f"{head} A {recorded!r} episode belongs at {home}: move it there ({move}; it then "
        f"replays with --emrd-modality={recorded}), then record the {asked!r} episode: {record}"
    )


def unreadable_message(
    *, cassette: str, response_index: int, response: dict[str, Any], command: str
) -> str:
    """The failure text of a recorded response the client could not read."""
    status = response.get("status", {}).get("code", "?")
    body = response.get("body", {}).get("string", b"")
    text = body.decode(errors="replace") if isinstance(body, bytes) else str(body)
    excerpt = " ".join(text.split())[:_BODY_EXCERPT]
    return (
        f"unreadable recorded response: response {response_index + 1} of cassette="
        f"{cassette!r} (HTTP {status}) was replayed and the client could not read it as a "
        f"reply (it asked for the same request again); the body starts {scrub(excerpt)!r}. "
        f"The file is damaged or was recorded from another endpoint; re-record it: {command}"
    )
