"""Reading a model's reply: tolerant of what real models write, strict about what matters.

**Repaired**, and named in :attr:`Reply.repairs` (:data:`REPAIRS`): syntax-only edits that
cannot change what any value means (a code fence, prose around the object, comments,
trailing commas, Python literals), and a position written in another notation, read in
metres without guessing (a list ``[x, z]``, a unit, a decimal comma; the table in
docs/interpretation/vocabulary.md). Numbers written as strings, a map given as a list of
objects with a ``label``/``id``/``name``, and missing optional keys are tolerated as is.

**Parse failures** (:attr:`Reply.error`; the episode keeps the previous map): no complete
JSON object, an object no repair makes valid (a missing comma, a ``...`` placeholder), no
``action`` or ``cognitive_map``, or a map entry whose position none of the above reads: any
repair would guess, and dropping the entry would look like forgetting the object.
:func:`parse_reply` never raises.
"""

from __future__ import annotations

import ast
import contextlib
import functools
import json
import math
import re
from dataclasses import dataclass
from typing import Any, Final

from pytest_emrd.trajectory import MapEntry

#: Longer replies are not searched for JSON (a runaway generation, not a reply).
MAX_REPLY_CHARS: Final = 200_000
#: Every repair :func:`parse_reply` may apply, in the order :attr:`Reply.repairs` lists them.
REPAIRS: Final[tuple[str, ...]] = (
    "fence",
    "prose",
    "comment",
    "trailing_comma",
    "python_literal",
    "position_list",
    "unit",
    "decimal_comma",
)
_FENCE = re.compile(r"```[A-Za-z0-9_-]*[ \t]*\n?(.*?)```", re.DOTALL)
#: JSON's names, which Python reads as names (its own ``True``/``None`` parse as constants).
_JSON_NAMES: Final = ("true", "false", "null")


@dataclass(frozen=True)
class Reply:
    """One model reply, as read."""

    observation: str = ""
    dedup_check: str = ""
    cognitive_map: tuple[MapEntry, ...] = ()
    action: str = ""
    reasoning: str | None = None
    error: str | None = None
    """Why the reply could not be read (the map is then not the model's); None if fine."""
    repairs: tuple[str, ...] = ()


_STRING = r"\"(?:[^\"\\]|\\.)*\"|'(?:[^'\\]|\\.)*'"
_COMMENT = r"//[^\n]*|/\*.*?(?:\*/|\Z)"
#: Inside an object: a string (skipped whole), a comment (skipped) or a brace.
_INSIDE = re.compile(rf"{_STRING}|{_COMMENT}|[{{}}]", re.DOTALL)
_DECODER = json.JSONDecoder()
#: A string (kept), a comment, or a trailing comma (before ``}``/``]``, comments between).
_CLEANED = re.compile(
    rf"({_STRING})|(?P<comment>{_COMMENT})|,(?=(?:\s|(?>{_COMMENT}))*[}}\]])", re.DOTALL
)
#: A coordinate written as text: a number (decimal point or comma), then maybe a metric unit.
_WRITTEN_NUMBER = re.compile(
    r"(?P<number>[+-]?(?:\d+(?:[.,]\d+)?|[.,]\d+)(?:[eE][+-]?\d+)?)\s*"
    r"(?P<unit>m|metres?|meters?|cm|centimetres?|centimeters?)?\.?",
    re.IGNORECASE,
)
_METRES_PER_UNIT: Final[dict[str, float]] = {
    **dict.fromkeys(("m", "metre", "metres", "meter", "meters"), 1.0),
    **dict.fromkeys(("cm", "centimetre", "centimetres", "centimeter", "centimeters"), 0.01),
}
#: A coordinate written as a JSON number is one of these (a tuple: ``isinstance`` is faster).
_NUMBERS: Final = (int, float)
#: Keys under which an entry may give its position as a list ``[x, z]``.
_POSITION_KEYS: Final = ("position", "pos", "xz", "coords", "coordinates", "location")


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


def _strip_comments_and_commas(text: str) -> tuple[str, set[str]]:
    """``text`` without comments and trailing commas outside strings, and which were found."""
    found: set[str] = set()

    def drop(match: re.Match[str]) -> str:
        if match.group(1) is not None:
            return match.group(1)
        comment = match.group("comment") is not None
        found.add("comment" if comment else "trailing_comma")
        return " " if comment else ""

    return _CLEANED.sub(drop, text), found


def _literal(node: ast.AST) -> Any:
    """Evaluate a JSON-like Python expression (dicts, lists, constants, signed numbers)."""
    if isinstance(node, ast.Constant) and isinstance(node.value, str | int | float | type(None)):
        return node.value
    if isinstance(node, ast.Name) and node.id in _JSON_NAMES:
        return json.loads(node.id)
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


def _load(candidate: str) -> tuple[Any, set[str]]:
    """(value, repairs): JSON as written, else JSON without comments and trailing commas,
    else a JSON-like Python literal; ``(None, set())`` when none of them reads."""
    with contextlib.suppress(ValueError, RecursionError):
        return json.loads(candidate), set()
    cleaned, repairs = _strip_comments_and_commas(candidate)
    if repairs:
        with contextlib.suppress(ValueError, RecursionError):
            return json.loads(cleaned), repairs
    try:
        value = _literal(ast.parse(cleaned.strip(), mode="eval").body)
    except (SyntaxError, ValueError, TypeError, RecursionError, MemoryError):
        return None, set()
    return value, repairs | {"python_literal"}


def _wrapping(text: str, start: int, end: int) -> tuple[str, ...]:
    """``fence`` and/or ``prose`` around the object at ``text[start:end]``."""
    for block in _FENCE.finditer(text):
        if block.start(1) <= start and end <= block.end(1):
            rest = text[: block.start()] + text[block.start(1) : start]
            rest += text[end : block.end(1)] + text[block.end() :]
            return ("fence", "prose") if rest.strip() else ("fence",)
    return ("prose",) if (text[:start] + text[end:]).strip() else ()


def _find_object(text: str) -> tuple[dict[str, Any] | None, set[str]]:
    """(object, repairs): among every balanced ``{...}`` span (of the whole reply and of each
    fenced block) that reads as an object, the last one with an ``action``, else the last."""
    stripped = text.strip()
    if stripped.startswith("{") and stripped.endswith("}"):
        try:
            whole = json.loads(stripped)
        except (ValueError, RecursionError):
            whole = None
        if isinstance(whole, dict) and "action" in whole:
            return whole, set()
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
        return None, set()
    with_action = [f for f in found if "action" in f[0]]
    obj, start, end, repairs = (with_action or found)[-1]
    return obj, repairs.union(_wrapping(text, start, end))


def _coordinate(value: Any, repairs: set[str]) -> float | None:
    """One coordinate in metres, the repairs that read it (``unit``, ``decimal_comma``) added
    to ``repairs``; None when it is no finite number, written or as a string."""
    if isinstance(value, _NUMBERS) and not isinstance(value, bool):
        return float(value) if math.isfinite(value) else None
    written = _WRITTEN_NUMBER.fullmatch(value.strip()) if isinstance(value, str) else None
    if written is None:
        return None
    number, unit = written.group("number"), (written.group("unit") or "").lower()
    metres = float(number.replace(",", "."))
    if unit:
        metres *= _METRES_PER_UNIT[unit]
    if not math.isfinite(metres):
        return None
    if "," in number:
        repairs.add("decimal_comma")
    if unit:
        repairs.add("unit")
    return metres


def _position(fields: Any, repairs: set[str]) -> tuple[float, float] | str:
    """``(x, z)`` of an entry (``x``/``z`` keys, else a list ``[x, z]``: the entry itself or
    under :data:`_POSITION_KEYS`), the repairs that read it added to ``repairs``; or why it has
    none."""
    if isinstance(fields, dict) and ("x" in fields or "z" in fields):
        x, z = fields.get("x"), fields.get("z")
        if type(x) is float is type(z) and math.isfinite(x) and math.isfinite(z):
            return x, z  # what _coordinate reads them as, without a call per coordinate
    else:
        pair = fields
        if isinstance(fields, dict):
            pair = next((fields[k] for k in _POSITION_KEYS if k in fields), None)
        if not isinstance(pair, list) or len(pair) != 2:
            written = json.dumps(fields, sort_keys=True)[:80]
            return f"has no x and z (nor a [x, z] list): {written}"
        x, z = pair
        repairs.add("position_list")
    read_x, read_z = _coordinate(x, repairs), _coordinate(z, repairs)
    if read_x is None or read_z is None:
        bad = ("x", x) if read_x is None else ("z", z)
        return f"has no number of metres as {bad[0]}: {json.dumps(bad[1])[:80]}"
    return read_x, read_z


def _text(value: Any) -> str:
    if value is None:
        return ""
    return value if isinstance(value, str) else json.dumps(value, sort_keys=True)


#: An entry built once while remembered: a reply mostly repeats the last one's map, and a frozen
#: dataclass takes a microsecond to build. Not for a zero coordinate: -0.0 == 0.0.
_remembered_entry: Final = functools.lru_cache(maxsize=1024)(MapEntry)


def _entry(label: str, fields: Any, repairs: set[str]) -> MapEntry | str:
    """The entry ``label``, the repairs that read its position added to ``repairs``; or why it
    cannot be read."""
    position = _position(fields, repairs)
    if isinstance(position, str):
        return f"cognitive_map entry {label!r} {position}"
    named = fields if isinstance(fields, dict) else {}  # a bare [x, z] names nothing
    kind = _text(named.get("type")).strip()  # per entry of every reply: no generator
    room, facing = _text(named.get("room")).strip(), _text(named.get("facing")).strip()
    make = _remembered_entry if all(position) else MapEntry
    return make(label, kind, *position, room or None, facing or None)


def _cognitive_map(raw: Any) -> tuple[tuple[MapEntry, ...], set[str]] | str:
    """The parsed map and the repairs that read its positions, or why it cannot be read."""
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
    entries, repairs = [], set()
    for label, fields in items:
        entry = _entry(label.strip(), fields, repairs)
        if isinstance(entry, str):
            return entry
        entries.append(entry)
    return tuple(entries), repairs


def parse_reply(text: str) -> Reply:
    """Read one reply. Never raises; an unreadable reply has ``error`` set.

    :param text: The model's reply as received.
    :returns: The :class:`Reply`: its fields, action and map, or ``error``.
    """
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
        "repairs": tuple(r for r in REPAIRS if r in repairs),
    }
    if not action:
        return Reply(**common, error="reply has no action")
    if "cognitive_map" not in obj:
        return Reply(**common, error="reply has no cognitive_map")
    parsed = _cognitive_map(obj["cognitive_map"])
    if isinstance(parsed, str):
        return Reply(**common, error=parsed)
    entries, read_with = parsed
    common["repairs"] = tuple(r for r in REPAIRS if r in repairs | read_with)
    return Reply(**common, cognitive_map=entries)
