"""Request bodies encoded once per message, handed to the cassette redactor in-process.

A request carries the whole history window every step (a base64 JPEG in each user turn), so
encoding the body, parsing it back to redact it and hashing its frames would handle each
message up to ten times. :func:`encode_body` gives the exact bytes ``httpx`` sends for
``json=body``, joining the UTF-8 encoding of each item of the body's top-level lists, each
computed once (a :class:`Fragment`), and remembers them (:func:`sent`), so the redactor
builds the canonical body from the same fragments, each redacted once, instead of parsing.

Items are immutable once encoded (:class:`~pytest_emrd.agent.Conversation` never changes a
message). Both tables are bounded, thread-safe, hold a reference to what they key (an ``id``
is never reused while remembered) and are checked by identity: a miss only costs time.
"""

from __future__ import annotations

import functools
import json
import operator
import threading
from collections import OrderedDict
from collections.abc import Callable
from dataclasses import dataclass
from json.encoder import encode_basestring
from typing import Any, Final

from pytest_emrd._lazy import remember

#: Fragments remembered (a window is 21 messages: this serves ~48 episodes at once).
_FRAGMENTS: Final = 1024
#: Sent bodies remembered until the redactor has seen them (a few per request in flight).
_BODIES: Final = 64


@functools.cache
def encoder(sort_keys: bool, ensure_ascii: bool, allow_nan: bool = True) -> Callable[[Any], str]:
    """``json.dumps(..., separators=(",", ":"))`` with these options, its encoder built once."""
    return json.JSONEncoder(
        separators=(",", ":"), sort_keys=sort_keys, ensure_ascii=ensure_ascii, allow_nan=allow_nan
    ).encode


#: ``httpx``'s encoding of ``json=``: the bytes a client would send without this module.
wire_json: Final = encoder(sort_keys=False, ensure_ascii=False, allow_nan=False)


@dataclass(slots=True, eq=False)
class Fragment:
    """One item of a sent body's top-level list: the item, the UTF-8 bytes of its wire JSON,
    and its canonical (redacted) bytes once the redactor has computed them."""

    item: Any
    wire: bytes
    canonical: bytes | None = None


_lock = threading.Lock()
_fragments: OrderedDict[int, Fragment] = OrderedDict()
_bodies: OrderedDict[int, tuple[bytes, Any, dict[str, Any]]] = OrderedDict()


def _remember(table: OrderedDict[Any, Any], key: Any, value: Any, capacity: int) -> None:
    with _lock:
        remember(table, key, value, capacity)


def spliced(tree: Any) -> bool:
    """Whether :func:`splice` applies: a JSON object with string keys only."""
    return isinstance(tree, dict) and all(isinstance(k, str) for k in tree)


#: Punctuation of a spliced object, as text and as bytes: comma, colon, brackets, braces.
_PUNCTUATION: Final = {
    False: (",", ":", "[", "]", "{", "}"),
    True: (b",", b":", b"[", b"]", b"{", b"}"),
}


def splice(
    tree: dict[str, Any],
    *,
    value: Callable[[Any], Any],
    item: Callable[[Any], Any],
    sort_keys: bool,
    binary: bool = False,
) -> Any:
    """``tree`` as compact JSON exactly as ``json.dumps`` joins an object (``ensure_ascii``
    off), each top-level list from its items' texts ``item(x)``, every other member from
    ``value(v)``, joined once. ``binary``: pieces and result are UTF-8 bytes."""
    comma, colon, left, right, opening, closing = _PUNCTUATION[binary]
    pieces = []
    for key in sorted(tree) if sort_keys else tree:
        name = encode_basestring(key)
        pieces += (comma, name.encode() if binary else name, colon)
        v = tree[key]
        if isinstance(v, list):
            pieces.append(left)
            for n, x in enumerate(v):
                pieces += (comma, item(x)) if n else (item(x),)
            pieces.append(right)
        else:
            pieces.append(value(v))
    if not pieces:
        return opening + closing
    pieces[0] = opening  # the first member's comma
    pieces.append(closing)
    return (b"" if binary else "").join(pieces)


def fragment(item: Any) -> Fragment:
    """The :class:`Fragment` of ``item``, encoded once while remembered."""
    hit = _fragments.get(id(item))  # one read is atomic; changes to the table take the lock
    if hit is not None and hit.item is item:
        return hit
    made = Fragment(item, wire_json(item).encode("utf-8"))
    _remember(_fragments, id(item), made, _FRAGMENTS)
    return made


def encode_body(body: Any) -> bytes:
    """The bytes ``httpx`` sends for ``json=body``, each list item encoded once; the redactor
    can then find ``body`` and its fragments again from the bytes (:func:`sent`)."""
    if not spliced(body):
        raw = wire_json(body).encode("utf-8")
        _remember(_bodies, id(raw), (raw, body, {}), _BODIES)
        return raw
    pieces = {k: [fragment(x) for x in v] if isinstance(v, list) else v for k, v in body.items()}
    raw = splice(
        pieces,
        value=lambda v: wire_json(v).encode("utf-8"),
        item=operator.attrgetter("wire"),
        sort_keys=False,
        binary=True,
    )
    _remember(_bodies, id(raw), (raw, body, pieces), _BODIES)
    return raw


def sent(raw: bytes) -> tuple[Any, dict[str, Any]] | None:
    """``(tree, pieces)`` :func:`encode_body` encoded into exactly this ``raw`` object (the
    pieces: the tree's members, each top-level list as its :class:`Fragment` list; empty
    when the tree was not spliced), else None."""
    hit = _bodies.get(id(raw))
    return (hit[1], hit[2]) if hit is not None and hit[0] is raw else None


def clear() -> None:
    """Forget every remembered encoding and body (tests, cold benchmarks)."""
    with _lock:
        _fragments.clear()
        _bodies.clear()
