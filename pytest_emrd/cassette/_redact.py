"""What a request looks like once it is safe to store and ready to match (docs/cassettes.md):
its *canonical* form (image payloads as frame digests, ``bytes:<sha256>`` for a frame this
process did not render; sorted-key compact JSON; configured key values removed) and its
match keys, ``strict`` (method, path, canonical body) and ``lenient`` (frames as
placeholders); a body that is not JSON never matches."""

from __future__ import annotations

import functools
import hashlib
import json
import re
from dataclasses import dataclass
from functools import cached_property
from json.encoder import encode_basestring
from typing import Any, Final

from pytest_emrd import _wire, frames
from pytest_emrd._scrub import scrub_bytes, secret_values

#: Request headers kept in a cassette; everything else (credentials included) is dropped.
KEPT_HEADERS: Final = frozenset({"content-type"})

#: A frame digest as redaction writes it (``pixels:`` or ``bytes:`` + SHA-256 hex).
DIGEST: Final = re.compile(r"^(?:pixels|bytes):[0-9a-f]{64}$")
_IMAGE_PLACEHOLDER: Final = "<image>"
_DATA_URL: Final = "data:image/"
_MIME_KEYS: Final = ("media_type", "mime_type", "mimeType")


@dataclass(frozen=True)
class Redacted:
    """The canonical form of one request body; the tree and the image count are derived on
    first use, so a body read back from a cassette is never parsed to be matched."""

    body: bytes
    """Canonical body bytes (sorted-key compact JSON), or the original bytes if not JSON."""
    parsed: bool
    """The body is JSON (only then does it get match keys)."""

    @cached_property
    def tree(self) -> Any:
        """The parsed canonical body (``None`` when the body is not JSON)."""
        return json.loads(self.body) if self.parsed else None

    @cached_property
    def images(self) -> int:
        """Number of image payloads in the body (each is a frame digest by now)."""
        return _count_digests(self.tree)


@dataclass(frozen=True)
class MatchKeys:
    """The keys a request is matched on, each computed on first use (``None`` for a body
    that is not JSON: it never matches)."""

    head: str
    """``METHOD path`` line that starts both keys."""
    redacted: Redacted

    @cached_property
    def strict(self) -> tuple[str, bytes] | None:
        """``(head, canonical body)``, compared as it is (hashing a body of tens of KB costs
        more than comparing it)."""
        return (self.head, self.redacted.body) if self.redacted.parsed else None

    @cached_property
    def lenient(self) -> str | None:
        if not self.redacted.parsed:
            return None
        text = self.head + canonical_json(_without_images(self.redacted.tree))
        return hashlib.sha256(text.encode()).hexdigest()


#: Sorted-key compact JSON, the one serialisation every key and cassette body uses.
canonical_json: Final = _wire.encoder(sort_keys=True, ensure_ascii=False)


def _image_mime(node: dict[str, Any]) -> bool:
    for key in _MIME_KEYS:
        mime = node.get(key)
        if isinstance(mime, str):
            return mime.startswith("image/")
    return False


def _redact_tree(node: Any) -> Any:
    if isinstance(node, str):
        if node.startswith(_DATA_URL):
            _, sep, payload = node.partition(";base64,")
            if sep:
                return frames.pixel_digest_for(payload)
        return node
    if isinstance(node, list | tuple):  # a tuple in a tree a client encodes is a JSON list
        return [_redact_tree(v) for v in node]
    if isinstance(node, dict):
        image = _image_mime(node)
        return {
            k: _payload(v) if image and k == "data" else _redact_tree(v) for k, v in node.items()
        }
    return node


def _payload(value: Any) -> Any:
    """The ``data`` of an image part (Anthropic, Gemini): base64 without a data-URL head."""
    if not isinstance(value, str):
        return _redact_tree(value)
    return value if DIGEST.match(value) else frames.pixel_digest_for(value)


def _count_digests(node: Any) -> int:
    if isinstance(node, dict):
        return sum(_count_digests(v) for v in node.values())
    if isinstance(node, list):
        return sum(_count_digests(v) for v in node)
    return int(isinstance(node, str) and DIGEST.match(node) is not None)


def _without_images(node: Any) -> Any:
    if isinstance(node, dict):
        return {k: _without_images(v) for k, v in node.items()}
    if isinstance(node, list):
        return [_without_images(v) for v in node]
    if isinstance(node, str) and DIGEST.match(node):
        return _IMAGE_PLACEHOLDER
    return node


def _canonical_bytes(value: Any, secrets: tuple[str, ...]) -> bytes:
    """``value`` redacted, serialised and scrubbed of ``secrets``. Redacting rebuilds the whole
    tree, so it runs only where the serialised text may hold an image (a data URL, an image
    MIME type): elsewhere it would change nothing (a replay's frames are digests already)."""
    text = canonical_json(value)
    if '"data:image/' in text or '"image/' in text:
        text = canonical_json(_redact_tree(value))
    return scrub_bytes(text.encode(), literal_only=True, secrets=secrets)


#: What a key value needs to lie across two members of a spliced body: every seam has one of
#: these characters on a side, or is the ``:`` before a value, where a value starts with ``:``.
_SEAMS: Final = frozenset('"{}[],')


@functools.lru_cache(maxsize=64)
def _member_wise(names: tuple[str, ...], secrets: tuple[str, ...]) -> bool:
    """Whether scrubbing each member of a body with members ``names`` alone removes every one
    of ``secrets`` as scrubbing the whole body does: none lies across a seam or in a name."""
    seams = any(_SEAMS.intersection(s) or s.startswith(":") for s in secrets)
    return not seams and not any(s in encode_basestring(n) for s in secrets for n in names)


def _canonical_fragment(piece: _wire.Fragment, secrets: tuple[str, ...]) -> bytes:
    """A member's canonical bytes, redacted and scrubbed once and kept on its fragment with the
    key values of the time, however many requests carry it (two threads may both compute it:
    the same bytes)."""
    if piece.canonical is None or piece.canonical[0] is not secrets:
        piece.canonical = secrets, _canonical_bytes(piece.item, secrets)
    return piece.canonical[1]


def _canonical_sent(tree: Any, pieces: dict[str, Any], secrets: tuple[str, ...]) -> bytes:
    """Canonical form of a body this process encoded (:mod:`pytest_emrd._wire`), its members
    scrubbed of ``secrets`` one by one (:func:`_member_wise`): each once, however many requests
    carry it. Byte for byte what parsing the body, redacting the whole tree and scrubbing it
    gives."""
    if not pieces or _image_mime(tree):
        return _canonical_bytes(tree, secrets)
    return _wire.splice(
        pieces, piece=lambda member: _canonical_fragment(member, secrets), sort_keys=True
    )


def redact_body(body: bytes | str | None) -> Redacted:
    """Canonical form of a request body (pure; see the module docstring).

    :param body: The request body as sent.
    :returns: Its :class:`Redacted` canonical form.
    """
    raw = body.encode() if isinstance(body, str) else (body or b"")
    secrets = secret_values()
    sent = _wire.sent(raw)
    if sent is not None and sent[2] is secrets:  # made by canonical_body, under these values
        return Redacted(body=raw, parsed=True)
    if sent is not None and _member_wise(tuple(sent[1]), secrets):
        return Redacted(body=_canonical_sent(*sent[:2], secrets), parsed=True)
    try:
        tree = json.loads(raw) if sent is None else sent[0]
    except (ValueError, UnicodeDecodeError):
        return Redacted(body=scrub_bytes(raw, literal_only=True), parsed=False)
    return Redacted(body=_canonical_bytes(tree, secrets), parsed=True)


def canonical_body(body: Any) -> bytes:
    """The canonical form of what a client sends for the JSON ``body`` (:func:`redact_body` of
    its wire bytes), made from ``body`` itself. A replay sends its requests in this form, as it
    sends its frames as their digests (nothing it sends leaves the process): no member is
    encoded for the wire, and :func:`redact_body` takes these bytes as they are.

    :param body: The request body, before encoding.
    :returns: Its canonical bytes.
    """
    secrets, pieces = secret_values(), _wire.pieces_of(body)
    if not _member_wise(tuple(pieces), secrets):
        pieces = {}  # a key value could lie across two members: the body is scrubbed whole
    raw = _canonical_sent(body, pieces, secrets)
    _wire.keep(raw, body, pieces, secrets)
    return raw


def match_keys(method: str, path: str, redacted: Redacted) -> MatchKeys:
    """The strict and lenient keys of a canonical request.

    :param method: The HTTP method.
    :param path: The request path.
    :param redacted: The body's canonical form (:func:`redact_body`).
    :returns: The :class:`MatchKeys`.
    """
    return MatchKeys(f"{method.upper()} {path}\n", redacted)


def canonical_keys(method: str, path: str, body: bytes) -> MatchKeys:
    """The keys of a body already in canonical, redacted form (read back from a cassette):
    nothing is parsed until a lenient key or a drift message needs the tree."""
    return match_keys(method, path, Redacted(body=body, parsed=True))


def scrub_headers(headers: Any) -> dict[str, str]:
    """Only the headers a cassette keeps (see :data:`KEPT_HEADERS`)."""
    return {k: v for k, v in dict(headers).items() if k.lower() in KEPT_HEADERS}
