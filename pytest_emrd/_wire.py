"""Request bodies encoded once per message, handed to the cassette redactor in-process.

A model request carries the whole history window every step (system prompt + the last ten
turns, a base64 JPEG in each user turn), so encoding the body, parsing it back to redact it
and hashing every frame in it would handle each message up to ten times. Here each message
is handled once:

* :func:`encode_body` gives the exact bytes ``httpx`` would send for ``json=body`` (compact,
  ``ensure_ascii=False``, no NaN), splicing in the encoding of each item of the body's
  top-level lists (``messages``, ``contents``) computed once per item (:func:`memo`);
* it remembers which tree those bytes came from (:func:`sent_tree`), so the redactor builds
  the canonical body from the same tree, item by item, instead of parsing it back.

Items are treated as immutable once encoded (:class:`~pytest_emrd.agent.Conversation` builds
each message once and never changes it). Both tables are bounded and thread-safe, hold a
reference to what they key (so an ``id`` is never reused while remembered) and are checked
by identity: a miss, or bytes this process did not build, only costs time (the redactor
then parses the body as before).
"""

from __future__ import annotations

import json
import threading
from collections import OrderedDict
from collections.abc import Callable, Hashable
from functools import partial
from typing import Any, Final

#: Item encodings remembered (a window is 21 messages; several episodes may run at once).
_ITEMS: Final = 2048
#: Sent bodies remembered until the redactor has seen them (a few per request in flight).
_BODIES: Final = 64

#: ``httpx``'s encoding of ``json=``: the bytes a client would send without this module.
wire_json: Final = partial(json.dumps, ensure_ascii=False, separators=(",", ":"), allow_nan=False)

_lock = threading.Lock()
_items: OrderedDict[tuple[int, Hashable], tuple[Any, Any]] = OrderedDict()
_bodies: OrderedDict[int, tuple[bytes, Any]] = OrderedDict()


def _remember(table: OrderedDict[Any, Any], key: Any, value: Any, capacity: int) -> None:
    with _lock:
        table[key] = value
        table.move_to_end(key)
        while len(table) > capacity:
            table.popitem(last=False)


def memo(item: Any, kind: Hashable, compute: Callable[[], Any]) -> Any:
    """``compute()`` for ``item``, computed once per ``(item, kind)`` while remembered."""
    key = (id(item), kind)
    with _lock:
        hit = _items.get(key)
    if hit is not None and hit[0] is item:
        return hit[1]
    value = compute()
    _remember(_items, key, (item, value), _ITEMS)
    return value


def spliced(tree: Any) -> bool:
    """Whether :func:`splice` applies: a JSON object with string keys only."""
    return isinstance(tree, dict) and all(isinstance(k, str) for k in tree)


def splice(
    tree: dict[str, Any],
    *,
    value: Callable[[Any], str],
    item: Callable[[Any], str],
    sort_keys: bool,
    ensure_ascii: bool = False,
) -> str:
    """``tree`` as compact JSON, member by member exactly as ``json.dumps`` joins an object
    (``separators=(",", ":")``), each top-level list from its items' texts ``item(x)`` and
    every other member from ``value(v)``."""
    members = []
    for key in sorted(tree) if sort_keys else tree:
        v = tree[key]
        text = "[" + ",".join(map(item, v)) + "]" if isinstance(v, list) else value(v)
        members.append(f"{json.dumps(key, ensure_ascii=ensure_ascii)}:{text}")
    return "{" + ",".join(members) + "}"


def _wire_item(item: Any) -> str:
    return memo(item, "wire", partial(wire_json, item))  # type: ignore[no-any-return]


def encode_body(body: Any) -> bytes:
    """The bytes ``httpx`` sends for ``json=body``, each list item encoded once; the redactor
    can then find ``body`` again from the bytes (:func:`sent_tree`)."""
    if spliced(body):
        text = splice(body, value=wire_json, item=_wire_item, sort_keys=False)
    else:
        text = wire_json(body)
    raw = text.encode("utf-8")
    _remember(_bodies, id(raw), (raw, body), _BODIES)
    return raw


def sent_tree(raw: bytes) -> Any | None:
    """The tree :func:`encode_body` encoded into exactly this ``raw`` object, else None."""
    with _lock:
        hit = _bodies.get(id(raw))
    return hit[1] if hit is not None and hit[0] is raw else None


def clear() -> None:
    """Forget every remembered encoding and body (tests, cold benchmarks)."""
    with _lock:
        _items.clear()
        _bodies.clear()
