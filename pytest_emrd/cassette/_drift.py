"""Explaining a replay that diverged: the first field where two canonical bodies differ."""

from __future__ import annotations

from typing import Any, Final

_PREVIEW: Final = 80
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


def drift_message(
    *, cassette: str, request_index: int, new_tree: Any, recorded_tree: Any | None, recorded: int
) -> str:
    """The failure text of a request that matches nothing in the cassette."""
    head = (
        f"environment or prompt drift: request {request_index + 1} of the episode matches "
        f"nothing in cassette={cassette!r}"
    )
    if new_tree is None:
        return f"{head}; its body is not JSON, and a body that cannot be parsed never matches."
    if recorded_tree is None:
        return (
            f"{head}; the cassette holds only {recorded} request(s), so the episode now makes "
            "more requests than when it was recorded (the world or the agent behaves differently)."
        )
    found = first_difference(new_tree, recorded_tree)
    if found is None:
        return (
            f"{head}; the body equals recorded request {request_index + 1}, "
            "which was already played."
        )
    where, now, then = found
    return f"{head}; first differing field {where}: now {_preview(now)}, recorded {_preview(then)}."
