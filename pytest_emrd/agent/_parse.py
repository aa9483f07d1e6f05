"""Reading a model's reply: tolerant of what real models write, strict about what matters.

Tolerated: Markdown code fences, prose before or after the JSON, single quotes, trailing
commas, Python spellings (``True``/``None``), numbers written as strings, a cognitive map
given as a list of objects with a ``label``/``id``/``name`` key, missing optional keys
(``observation``, ``dedup_check``, ``reasoning``), map entries without ``room``/``facing``.

Strict: the reply must hold one JSON object with an ``action`` string and a
``cognitive_map``; otherwise :attr:`Reply.error` says why, and the episode loop keeps the
previous map as the model's belief. Map entries without finite numeric ``x`` and ``z`` are
not positions and are left out. :func:`parse_reply` never raises.
"""

from __future__ import annotations

import ast
import json
import math
import re
from dataclasses import dataclass
from typing import Any, Final

from pytest_emrd.trajectory import MapEntry

#: Replies longer than this are not searched for JSON (a runaway generation, not a reply).
MAX_REPLY_CHARS: Final = 200_000
_FENCE = re.compile(r"```[A-Za-z0-9_-]*[ \t]*\n?(.*?)```", re.DOTALL)
_TRAILING_COMMA = re.compile(r",(\s*[}\]])")
_LITERAL_NAMES: Final[dict[str, Any]] = {
    "true": True,
    "false": False,
    "null": None,
    "True": True,
    "False": False,
    "None": None,
}


@dataclass(frozen=True)
class Reply:
    """One model reply, as read."""

    observation: str = ""
    dedup_check: str = ""
    cognitive_map: tuple[MapEntry, ...] = ()
    action: str = ""
    """The action text, stripped (``Goto(Doorway_1)``); empty if none could be read."""
    reasoning: str | None = None
    error: str | None = None
    """Why the reply could not be read (the map is then not the model's); None if fine."""


def _balanced_objects(text: str) -> list[str]:
    """Every top-level ``{...}`` span of ``text``, string-aware for both quote kinds."""
    spans: list[str] = []
    depth, start, quote, escaped = 0, -1, "", False
    for i, ch in enumerate(text):
        if quote:
            if escaped:
                escaped = False
            elif ch == "\\":
                escaped = True
            elif ch == quote:
                quote = ""
        elif ch in "\"'" and depth > 0:
            quote = ch
        elif ch == "{":
            if depth == 0:
                start = i
            depth += 1
        elif ch == "}" and depth > 0:
            depth -= 1
            if depth == 0:
                spans.append(text[start : i + 1])
    return spans


def _literal(node: ast.AST) -> Any:
    """Evaluate a JSON-like Python expression (dicts, lists, constants, signed numbers)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str | int | float | type(None)):
        return node.value
    if isinstance(node, ast.Name) and node.id in _LITERAL_NAMES:
        return _LITERAL_NAMES[node.id]
    if isinstance(node, ast.Dict):
        if any(k is None for k in node.keys):
            raise ValueError("dict unpacking is not JSON")
        return {_literal(k): _literal(v) for k, v in zip(node.keys, node.values, strict=True)}
    if isinstance(node, ast.List | ast.Tuple):
        return [_literal(e) for e in node.elts]
    if isinstance(node, ast.UnaryOp) and isinstance(node.op, ast.USub | ast.UAdd):
        value = _literal(node.operand)
        if isinstance(value, int | float) and not isinstance(value, bool):
            return -value if isinstance(node.op, ast.USub) else value
    raise ValueError(f"not a JSON value: {type(node).__name__}")


def _load(candidate: str) -> Any:
    """JSON, else JSON without trailing commas, else a JSON-like Python literal; or None."""
    for text in (candidate, _TRAILING_COMMA.sub(r"\1", candidate)):
        try:
            return json.loads(text)
        except (ValueError, RecursionError):
            pass
    try:
        return _literal(ast.parse(candidate.strip(), mode="eval").body)
    except (SyntaxError, ValueError, TypeError, RecursionError, MemoryError):
        return None


def _find_object(text: str) -> dict[str, Any] | None:
    """The reply's JSON object: the whole reply if it is one, else fenced blocks and
    balanced ``{...}`` spans, preferring the last one that has an action."""
    stripped = text.strip()
    if stripped.startswith("{") and stripped.endswith("}"):
        try:
            whole = json.loads(stripped)
        except (ValueError, RecursionError):
            whole = None
        if isinstance(whole, dict) and "action" in whole:
            return whole
    candidates = [m.group(1) for m in _FENCE.finditer(text)]
    candidates += [s for block in candidates for s in _balanced_objects(block)]
    candidates += _balanced_objects(text)
    found = [obj for c in candidates if isinstance(obj := _load(c), dict)]
    with_action = [obj for obj in found if "action" in obj]
    if with_action:
        return with_action[-1]
    return found[-1] if found else None


def _number(value: Any) -> float | None:
    if isinstance(value, bool):
        return None
    if isinstance(value, str):
        try:
            value = float(value.strip().removesuffix("m").strip())
        except ValueError:
            return None
    if isinstance(value, int | float) and math.isfinite(value):
        return float(value)
    return None


def _text(value: Any) -> str:
    if value is None:
        return ""
    return value if isinstance(value, str) else json.dumps(value, sort_keys=True)


def _entry(label: str, fields: Any) -> MapEntry | None:
    if not isinstance(fields, dict):
        return None
    x, z = _number(fields.get("x")), _number(fields.get("z"))
    if x is None or z is None:
        return None
    return MapEntry(
        label=label,
        object_type=_text(fields.get("type")).strip(),
        x=x,
        z=z,
        room=_text(fields.get("room")).strip() or None,
        facing=_text(fields.get("facing")).strip() or None,
    )


def _cognitive_map(raw: Any) -> tuple[MapEntry, ...] | str:
    """The parsed map, or the reason it cannot be read."""
    if isinstance(raw, list):
        items = []
        for item in raw:
            if not isinstance(item, dict):
                return "cognitive_map is a list whose items are not objects"
            label = next((item[k] for k in ("label", "id", "name") if item.get(k)), None)
            if label is None:
                return "cognitive_map list item without label/id/name"
            items.append((_text(label), item))
    elif isinstance(raw, dict):
        items = [(str(k), v) for k, v in raw.items()]
    else:
        return f"cognitive_map is {type(raw).__name__}, not an object"
    entries = [e for label, fields in items if (e := _entry(label.strip(), fields))]
    return tuple(entries)


def parse_reply(text: str) -> Reply:
    """Read one reply. Never raises; an unreadable reply has ``error`` set."""
    if not isinstance(text, str) or not text.strip():
        return Reply(error="empty reply")
    if len(text) > MAX_REPLY_CHARS:
        return Reply(error=f"reply of {len(text)} characters exceeds {MAX_REPLY_CHARS}")
    obj = _find_object(text)
    if obj is None:
        return Reply(error="no JSON object found in the reply")
    action = _text(obj.get("action")).strip()
    reasoning = _text(obj["reasoning"]).strip() if obj.get("reasoning") is not None else None
    common = {
        "observation": _text(obj.get("observation")),
        "dedup_check": _text(obj.get("dedup_check")),
        "action": action,
        "reasoning": reasoning,
    }
    if not action:
        return Reply(**common, error="reply has no action")
    if "cognitive_map" not in obj:
        return Reply(**common, error="reply has no cognitive_map")
    parsed = _cognitive_map(obj["cognitive_map"])
    if isinstance(parsed, str):
        return Reply(**common, error=parsed)
    return Reply(**common, cognitive_map=parsed)
