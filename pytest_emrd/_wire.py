"""Request bodies encoded once per message, handed to the cassette redactor in-process.

A request carries the whole history window every step (a base64 JPEG in each user turn), so
encoding the body, parsing it back to redact it and hashing its frames would handle each
message up to ten times. :func:`encode_body` gives the exact bytes ``httpx`` sends for
``json=body``, joining the UTF-8 encoding of each member of the body (each item of a
top-level list), each computed once (a :class:`Fragment`), and remembers them (:func:`sent`),
so the redactor builds the canonical body from the same fragments, each redacted once,
instead of parsing. A replay sends the canonical body itself (the redactor's
``canonical_body``), whose fragments are never encoded for the wire.

Members are immutable once encoded (:class:`~pytest_emrd.agent.Conversation` never changes a
message). Both tables are bounded, thread-safe, hold a reference to what they key (an ``id``
is never reused while remembered) and are checked by identity: a miss only costs time.
"""

from __future__ import annotations

import functools
import json
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
    """One member of a sent body (or item of a top-level list): the item, the UTF-8 bytes of its
    wire JSON and its canonical (redacted) bytes, each once something has asked for them, the
    canonical ones with the secret values they are scrubbed of."""

    item: Any
    wire: bytes | None = None
    canonical: tuple[tuple[str, ...], bytes] | None = None


_lock = threading.Lock()
_fragments: OrderedDict[int, Fragment] = OrderedDict()
_bodies: OrderedDict[int, tuple[bytes, Any, dict[str, Any], Any]] = OrderedDict()


def _remember(table: OrderedDict[Any, Any], key: Any, value: Any, capacity: int) -> None:
    with _lock:
        remember(table, key, value, capacity)


def splice(
    pieces: dict[str, Fragment | list[Fragment]],
    *,
    piece: Callable[[Fragment], bytes],
    sort_keys: bool,
) -> bytes:
    """The object :func:`encode_body` split into ``pieces`` (not empty) as compact UTF-8 JSON,
    exactly as ``json.dumps`` joins an object (``ensure_ascii`` off), each fragment's bytes from
    ``piece(fragment)``. The fragments are joined once (a body is tens of KB): the braces, a
    list's brackets and a member's name go on the first and last fragments."""
    members = []
    for key in sorted(pieces) if sort_keys else pieces:
        member, name = pieces[key], encode_basestring(key).encode()
        if not isinstance(member, list):
            members.append(b"%b:%b" % (name, piece(member)))
            continue
        values = list(map(piece, member)) or [b""]
        values[0] = b"%b:[%b" % (name, values[0])
        values[-1] += b"]"
        members += values
    members[0] = b"{" + members[0]
    members[-1] += b"}"
    return b",".join(members)


def fragment(item: Any) -> Fragment:
    """The :class:`Fragment` of ``item``, made once while remembered."""
    hit = _fragments.get(id(item))  # one read is atomic; changes to the table take the lock
    if hit is not None and hit.item is item:
        return hit
    made = Fragment(item)
    _remember(_fragments, id(item), made, _FRAGMENTS)
    return made


def _fragment_wire(piece: Fragment) -> bytes:
    if piece.wire is None:  # two threads may both compute it: the same bytes
        piece.wire = wire_json(piece.item).encode("utf-8")
    return piece.wire


def pieces_of(body: Any) -> dict[str, Any]:
    """``body``'s members as :class:`Fragment` (each top-level list as a list of them); empty
    unless :func:`splice` applies (a JSON object with string keys only)."""
    if not (isinstance(body, dict) and all(isinstance(k, str) for k in body)):
        return {}
    return {
        k: [fragment(x) for x in v] if isinstance(v, list) else fragment(v) for k, v in body.items()
    }


def encode_body(body: Any) -> bytes:
    """The bytes ``httpx`` sends for ``json=body``, each member (each item of a top-level
    list) encoded once; the redactor can then find ``body`` and its fragments again from the
    bytes (:func:`sent`)."""
    pieces = pieces_of(body)
    if not pieces:
        raw = wire_json(body).encode("utf-8")
    else:
        raw = splice(pieces, piece=_fragment_wire, sort_keys=False)
    keep(raw, body, pieces)
    return raw


def keep(raw: bytes, body: Any, pieces: dict[str, Any], form: Any = None) -> None:
    """Remember that ``raw`` is what was sent for ``body`` split into ``pieces``, and ``form``:
    what else its maker knows of it (the redactor: the secret values it is canonical under)."""
    _remember(_bodies, id(raw), (raw, body, pieces, form), _BODIES)


def sent(raw: bytes) -> tuple[Any, dict[str, Any], Any] | None:
    """``(tree, pieces, form)`` :func:`keep` remembered for exactly this ``raw`` object (the
    pieces: :func:`pieces_of` the tree), else None."""
    hit = _bodies.get(id(raw))
    return hit[1:] if hit is not None and hit[0] is raw else None


def clear() -> None:
    """Forget every remembered encoding and body (tests, cold benchmarks)."""
    with _lock:
        _fragments.clear()
        _bodies.clear()
