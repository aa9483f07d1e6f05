"""In-process hand-over of frame identities from the world to the cassette redactor.

A cassette keys a frame by a digest of its rendered *pixels*, never by JPEG bytes, so that a
recording replays across machines and Pillow versions. The agent registers each data-URL
payload it sends with its pixel digest (:func:`register`); the redactor, seeing only the HTTP
body, looks it up (:func:`pixel_digest_for`); an unknown payload falls back to a ``bytes:``
digest of itself. A replay never encodes a frame: its requests carry :func:`by_digest`, the
very string the redactor would have put there. The table is bounded and thread-safe.
"""

from __future__ import annotations

import hashlib
import threading
from collections import OrderedDict
from typing import Final

from pytest_emrd._lazy import remember

#: What a frame's pixel digest is prefixed with in a canonical request.
PIXELS: Final = "pixels:"
_CAPACITY: Final = 4096
_lock = threading.Lock()
_table: OrderedDict[str, str] = OrderedDict()


def _payload_key(b64_payload: str | bytes) -> str:
    raw = b64_payload.encode() if isinstance(b64_payload, str) else b64_payload
    return hashlib.sha256(raw).hexdigest()


def register(b64_payload: str | bytes, pixel_digest: str) -> None:
    """Remember that this base64 image payload shows the frame with ``pixel_digest``."""
    key = _payload_key(b64_payload)
    with _lock:
        remember(_table, key, pixel_digest, _CAPACITY)


def by_digest(pixel_digest: str) -> str:
    """The frame with ``pixel_digest`` as a replayed request carries it: ``pixels:<sha256>``."""
    return PIXELS + pixel_digest


def pixel_digest_for(b64_payload: str | bytes) -> str:
    """``pixels:<sha256>`` for a registered payload, else ``bytes:<sha256 of payload>``."""
    key = _payload_key(b64_payload)
    with _lock:
        digest = _table.get(key)
    return by_digest(digest) if digest else f"bytes:{key}"


def clear() -> None:
    """Forget every registered frame (tests)."""
    with _lock:
        _table.clear()
