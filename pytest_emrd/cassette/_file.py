"""The cassette file: a vcrpy cassette in vcrpy's own JSON serializer, compressed with xz
(fields: docs/cassettes.md); ``metadata.emrd.digest`` covers the protocol and every
interaction, so a file edited by hand is refused on load. JSON, not YAML: it loads ten times
faster. The same traffic always gives the same bytes (sorted keys; xz single-threaded,
LZMA2, 1 MiB dictionary, CRC32, no timestamp). A gzip cassette is read too."""

from __future__ import annotations

import gzip
import hashlib
import json
import lzma
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

from vcr.request import Request
from vcr.serialize import CASSETTE_FORMAT_VERSION
from vcr.serializers import compat, jsonserializer

#: The file name ending of a cassette.
SUFFIX: Final = ".json.xz"
_XZ_MAGIC: Final = b"\xfd7zXZ\x00"
_GZIP_MAGIC: Final = b"\x1f\x8b"
#: LZMA2 at its strongest setting with no 4-byte alignment assumed (``pb=0``: the document is
#: text); a 1 MiB dictionary holds a whole episode's repeated history windows.
_XZ_FILTERS: Final = (
    {"id": lzma.FILTER_LZMA2, "preset": 9 | lzma.PRESET_EXTREME, "dict_size": 1 << 20, "pb": 0},
)
#: How the document of a cassette an older release wrote (format 1 or 2) starts.
LEGACY_HEAD: Final = '{"format":"emrd-cassette/'


class FormatError(ValueError):
    """The bytes are not a readable cassette; the message says what is wrong."""


class LegacyFormatError(FormatError):
    """A cassette an older pytest-emrd wrote (format ``emrd-cassette/1`` or ``/2``)."""


class IntegrityError(FormatError):
    """A cassette whose interactions no longer match the digest recorded with them."""


@dataclass(frozen=True)
class CassetteData:
    """Everything one cassette file holds."""

    protocol: str
    requests: tuple[Request, ...]
    responses: tuple[dict[str, Any], ...]
    raw: frozenset[int] = frozenset()
    """Indices of the requests whose body is not canonical JSON (keyed by redacting again)."""


def _text(data: bytes | str | None) -> str | None:
    """A body as vcrpy's JSON serializer stores it: text (a cassette holds UTF-8 only)."""
    if data is None or isinstance(data, str):
        return data
    try:
        return data.decode()
    except UnicodeDecodeError:
        raise FormatError(
            f"a body is not UTF-8 text ({data[:20]!r}...); vcrpy's JSON serializer stores text"
        ) from None


def _sorted(mapping: dict[str, Any]) -> dict[str, Any]:
    return {k: mapping[k] for k in sorted(mapping)}


def _interaction(request: Request, response: dict[str, Any]) -> dict[str, Any]:
    """One interaction as vcrpy's ``serialize`` builds it, keys sorted (``response`` itself
    is left as it is)."""
    body = {**response["body"], "string": _text(response["body"]["string"])}
    headers = {k: list(v) for k, v in response["headers"].items()}
    return {
        "request": {
            "body": _text(request.body),
            "headers": _sorted({k: [v] for k, v in request.headers.items()}),
            "method": request.method,
            "uri": request.uri,
        },
        "response": _sorted(
            {
                **response,
                "body": _sorted(body),
                "headers": _sorted(headers),
                "status": _sorted(dict(response["status"])),
            }
        ),
    }


def digest(protocol: str, interactions: Sequence[dict[str, Any]]) -> str:
    """SHA-256 of the protocol and the interactions as stored: each part hashed with its length
    in front (the protocol; per interaction its request and response without bodies as
    sorted-key JSON, then each body's text or ``null``; cheaper than serialising it again)."""
    h = hashlib.sha256()

    def part(text: str) -> None:
        data = text.encode(errors="surrogatepass")  # a hand-edited "\ud800" is hashed too
        h.update(b"%d:" % len(data))
        h.update(data)

    part(protocol)
    for item in interactions:
        request, response = item["request"], item["response"]
        bodies = (request["body"], response["body"]["string"])
        part(json.dumps([{**request, "body": 0}, {**response, "body": 0}], sort_keys=True))
        for body in bodies:
            part("null" if body is None else f"={body}")
    return "sha256:" + h.hexdigest()


def document(data: CassetteData) -> dict[str, Any]:
    """The vcrpy cassette document of ``data`` (what :func:`encode` serialises)."""
    interactions = [
        _interaction(request, response)
        for request, response in zip(data.requests, data.responses, strict=True)
    ]
    emrd: dict[str, Any] = {"digest": digest(data.protocol, interactions)}
    if data.raw:
        emrd["raw"] = sorted(data.raw)
    emrd["protocol"] = data.protocol
    return {
        "interactions": interactions,
        "metadata": {"emrd": emrd},
        "version": CASSETTE_FORMAT_VERSION,
    }


def encode(data: CassetteData) -> bytes:
    """The xz-compressed vcrpy JSON cassette of ``data`` (deterministic)."""
    text = jsonserializer.serialize(document(data))
    return lzma.compress(
        text.encode(), format=lzma.FORMAT_XZ, check=lzma.CHECK_CRC32, filters=_XZ_FILTERS
    )


def decompress(blob: bytes) -> str:
    """The text inside ``blob``, xz or gzip (told by the magic bytes)."""
    try:
        if blob.startswith(_XZ_MAGIC):
            return lzma.decompress(blob, format=lzma.FORMAT_XZ).decode()
        if blob.startswith(_GZIP_MAGIC):
            return gzip.decompress(blob).decode()
    except (OSError, EOFError, zlib.error, lzma.LZMAError, UnicodeDecodeError) as exc:
        raise FormatError(f"not a readable xz or gzip file ({exc})") from exc
    raise FormatError(f"not an xz- or gzip-compressed file (it starts {blob[:8]!r})")


def decode(blob: bytes) -> CassetteData:
    """Inverse of :func:`encode` (a gzip file is read too): :class:`LegacyFormatError` for a file
    an older release wrote, :class:`IntegrityError` when the interactions or the protocol no
    longer match their digest, :class:`FormatError` for anything else that is not a cassette."""
    text = decompress(blob)
    if text.startswith(LEGACY_HEAD):
        raise LegacyFormatError(
            "it is in a format an older pytest-emrd wrote (emrd-cassette/1 or /2), under an "
            "earlier protocol; it cannot replay with this release"
        )
    try:
        loaded = jsonserializer.deserialize(text)
    except ValueError as exc:
        raise FormatError(f"not valid JSON ({exc})") from exc
    try:
        emrd = loaded["metadata"]["emrd"]
        interactions = loaded["interactions"]
        protocol = str(emrd["protocol"])
        found = digest(protocol, interactions)
    except (KeyError, TypeError) as exc:
        raise FormatError(
            f"not a pytest-emrd vcrpy cassette (no {exc} in interactions or metadata.emrd)"
        ) from exc
    if found != emrd.get("digest"):
        raise IntegrityError("its interactions do not match the digest recorded with them")
    try:
        requests = tuple(Request(**item["request"]) for item in interactions)
        responses = tuple(compat.convert_to_bytes(item["response"]) for item in interactions)
    except (KeyError, TypeError) as exc:
        raise FormatError(f"malformed interaction ({type(exc).__name__}: {exc})") from exc
    return CassetteData(protocol, requests, responses, frozenset(emrd.get("raw", ())))
