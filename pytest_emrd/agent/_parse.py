"""Reading a model's reply: tolerant of what real models write, strict about what matters.

**Repaired** (the reply is read, and :attr:`Reply.repairs` names every repair, so a run can
count them; see :data:`REPAIRS`):

* ``fence`` — the JSON sits in a Markdown code fence (```` ```json ... ``` ````);
* ``prose`` — text before or after the JSON object (or its fence);
* ``comment`` — ``// ...`` line comments or ``/* ... */`` block comments outside strings;
* ``trailing_comma`` — a comma right before ``}`` or ``]``;
* ``python_literal`` — single-quoted strings or Python spellings (``True``/``None``).

Each is a *syntax-only* edit whose reading is unambiguous: removing it cannot change what any
value of the object means. Also tolerated, as schema leniency rather than repairs: numbers
written as strings (``"1.5"``, ``"2 m"``), a cognitive map given as a list of objects with a
``label``/``id``/``name`` key, missing optional keys (``observation``, ``dedup_check``,
``reasoning``), map entries without ``room``/``facing``.

**Parse failures** (:attr:`Reply.error` says why; the episode loop keeps the previous map as the
model's belief): no complete JSON object (prose only; a reply cut off mid-object, as at the
token limit), an object no repair above makes valid (a missing comma between two values,
unquoted keys, a ``...`` placeholder standing for elided entries), or an object without an
``action`` string or a ``cognitive_map``. Those are not repaired because any repair would guess
content: where a comma was missing, what ``...`` stood for, what a cut-off map still held. Map
entries without finite numeric ``x`` and ``z`` are not positions and are left out.
:func:`parse_reply` never raises.
"""

from __future__ import annotations

import ast
import json
import math
import re
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final

from pytest_emrd.trajectory import MapEntry

#: Replies longer than this are not searched for JSON (a runaway generation, not a reply).
MAX_REPLY_CHARS: Final = 200_000
#: Every repair :func:`parse_reply` may apply, in the order :attr:`Reply.repairs` lists them.
REPAIRS: Final[tuple[str, ...]] = ("fence", "prose", "comment", "trailing_comma", "python_literal")
_FENCE = re.compile(r"```[A-Za-z0-9_-]*[ \t]*\n?(.*?)```", re.DOTALL)
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
    repairs: tuple[str, ...] = ()
    """Repairs applied to read the object (names from :data:`REPAIRS`, in that order)."""


_STRING = r"\"(?:[^\"\\]|\\.)*\"|'(?:[^'\\]|\\.)*'"
_COMMENT = r"//[^\n]*|/\*.*?(?:\*/|\Z)"
#: Inside an object: a string (skipped whole), a comment (skipped) or a brace.
_INSIDE = re.compile(rf"{_STRING}|{_COMMENT}|[{{}}]", re.DOTALL)
_COMMENTS = re.compile(rf"({_STRING})|{_COMMENT}", re.DOTALL)
_TRAILING_COMMAS = re.compile(rf"({_STRING})|,(?=\s*[}}\]])", re.DOTALL)
#: Where a comment or a trailing comma could be (in a string or not): without one, there is none.
_MAYBE_COMMENT = re.compile(r"//|/\*")
_MAYBE_TRAILING_COMMA = re.compile(r",\s*[}\]]")
_DECODER = json.JSONDecoder()


def _json_end(text: str, start: int) -> int | None:
    """Where the JSON object starting at ``start`` ends, if it is valid JSON. Its span is then
    the one the token scan of :func:`_balanced_objects` finds (JSON strings are the scan's
    double-quoted strings, and JSON has no other quote, no comment, no unpaired brace), at C
    speed: most replies are valid JSON, in a fence or after prose or not."""
    try:
        return _DECODER.raw_decode(text, start)[1]
    except (ValueError, RecursionError):
        return None


def _balanced_objects(text: str) -> list[tuple[int, int]]:
    """``(start, end)`` of every top-level ``{...}`` span of ``text``. Inside an object, strings
    (both quote kinds) and comments are skipped whole, so a brace or an apostrophe in them
    does not count; outside, only braces matter (prose may hold any quote)."""
    spans: list[tuple[int, int]] = []
    start = text.find("{")
    while start >= 0:
        end = _json_end(text, start)
        if end is not None:
            spans.append((start, end))
            start = text.find("{", end)
            continue
        depth, at = 1, start + 1
        while depth and (token := _INSIDE.search(text, at)) is not None:
            at = token.end()
            if token.group() == "{":
                depth += 1
            elif token.group() == "}":
                depth -= 1
        if depth:
            return spans
        spans.append((start, at))
        start = text.find("{", at)
    return spans


def _strip_comments_and_commas(text: str) -> tuple[str, tuple[str, ...]]:
    """``text`` without comments and trailing commas outside strings, and which were found."""
    found: list[str] = []

    def drop(kind: str, replacement: str) -> Callable[[re.Match[str]], str]:
        def sub(match: re.Match[str]) -> str:
            if match.group(1) is not None:
                return match.group(1)
            found.append(kind)
            return replacement

        return sub

    if _MAYBE_COMMENT.search(text):
        text = _COMMENTS.sub(drop("comment", " "), text)
    if _MAYBE_TRAILING_COMMA.search(text):
        text = _TRAILING_COMMAS.sub(drop("trailing_comma", ""), text)
    return text, tuple(r for r in REPAIRS if r in found)


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


def _load(candidate: str) -> tuple[Any, tuple[str, ...]]:
    """(value, repairs): JSON as written, else JSON without comments and trailing commas,
    else a JSON-like Python literal; ``(None, ())`` when none of them reads."""
    try:
        return json.loads(candidate), ()
    except (ValueError, RecursionError):
        pass
    cleaned, repairs = _strip_comments_and_commas(candidate)
    if repairs:
        try:
            return json.loads(cleaned), repairs
        except (ValueError, RecursionError):
            pass
    try:
        value = _literal(ast.parse(cleaned.strip(), mode="eval").body)
    except (SyntaxError, ValueError, TypeError, RecursionError, MemoryError):
        return None, ()
    return value, (*repairs, "python_literal")


def _wrapping(text: str, start: int, end: int) -> tuple[str, ...]:
    """``fence`` and/or ``prose`` around the object at ``text[start:end]``."""
    for block in _FENCE.finditer(text):
        if block.start(1) <= start and end <= block.end(1):
            rest = text[: block.start()] + text[block.start(1) : start]
            rest += text[end : block.end(1)] + text[block.end() :]
            return ("fence", "prose") if rest.strip() else ("fence",)
    return ("prose",) if (text[:start] + text[end:]).strip() else ()


def _find_object(text: str) -> tuple[dict[str, Any] | None, tuple[str, ...]]:
    """(object, repairs): among every balanced ``{...}`` span (of the whole reply and of each
    fenced block) that reads as an object, the last one with an ``action``, else the last."""
    stripped = text.strip()
    if stripped.startswith("{") and stripped.endswith("}"):
        try:
            whole = json.loads(stripped)
        except (ValueError, RecursionError):
            whole = None
        if isinstance(whole, dict) and "action" in whole:
            return whole, ()
    spans = set(_balanced_objects(text))
    for block in _FENCE.finditer(text):
        offset = block.start(1)
        spans.update((offset + s, offset + e) for s, e in _balanced_objects(block.group(1)))
    found = []
    for start, end in sorted(spans):
        value, repairs = _load(text[start:end])
        if isinstance(value, dict):
            found.append((value, start, end, repairs))
    if not found:
        return None, ()
    with_action = [f for f in found if "action" in f[0]]
    obj, start, end, repairs = (with_action or found)[-1]
    applied = {*_wrapping(text, start, end), *repairs}
    return obj, tuple(r for r in REPAIRS if r in applied)


def _number(value: Any) -> float | None:
    if type(value) is float:  # the common case first: a map holds dozens of coordinates
        return value if math.isfinite(value) else None
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
    get = fields.get
    return MapEntry(
        label,
        _text(get("type")).strip(),
        x,
        z,
        _text(get("room")).strip() or None,
        _text(get("facing")).strip() or None,
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
    obj, repairs = _find_object(text)
    if obj is None:
        return Reply(error="no JSON object found in the reply")
    action = _text(obj.get("action")).strip()
    reasoning = _text(obj["reasoning"]).strip() if obj.get("reasoning") is not None else None
    common = {
        "observation": _text(obj.get("observation")),
        "dedup_check": _text(obj.get("dedup_check")),
        "action": action,
        "reasoning": reasoning,
        "repairs": repairs,
    }
    if not action:
        return Reply(**common, error="reply has no action")
    if "cognitive_map" not in obj:
        return Reply(**common, error="reply has no cognitive_map")
    parsed = _cognitive_map(obj["cognitive_map"])
    if isinstance(parsed, str):
        return Reply(**common, error=parsed)
    return Reply(**common, cognitive_map=parsed)
