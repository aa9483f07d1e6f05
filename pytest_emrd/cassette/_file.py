"""The cassette file: a vcrpy cassette in vcrpy's own JSON serializer, compressed with xz
(fields: docs/cassettes.md); ``metadata.emrd.digest`` covers the whole file (metadata
included), so a file changed by accident is refused on load (a digest anyone can recompute
detects accidents, not forgery: docs/security.md). A file is inflated up to a cap and checked
against a small schema before any field is used. JSON, not YAML: it loads ten times
faster. It is read with orjson, which parses an episode's few MB of escaped request bodies
in half the time ``json`` takes (the same objects: a cassette holds text and whole numbers
only). The same traffic always gives the same bytes (sorted keys; xz single-threaded,
LZMA2, 1 MiB dictionary, CRC32, no timestamp). A gzip cassette is read too."""

from __future__ import annotations

import hashlib
import io
import json
import lzma
import zlib
from dataclasses import dataclass
from typing import Any, BinaryIO, Final

import orjson
from vcr.request import Request
from vcr.serialize import CASSETTE_FORMAT_VERSION
from vcr.serializers import compat, jsonserializer

#: The file name ending of a cassette.
SUFFIX: Final = ".json.xz"
_XZ_MAGIC: Final = b"\xfd7zXZ\x00"
_GZIP_MAGIC: Final = b"\x1f\x8b"
#: Most text a cassette file may inflate to (a 50-step episode is a few MB; a bomb is cut here).
MAX_TEXT_BYTES: Final = 64 << 20
_CHUNK: Final = 1 << 16
#: How the digest of the whole file starts; an older release's digest (of the interactions
#: only) starts ``sha256:``.
DIGEST_PREFIX: Final = "sha256-file:"
#: The digest while the document is hashed: the file is hashed with its digest reading this.
_UNSET: Final = DIGEST_PREFIX + "0" * 64
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


def document(data: CassetteData) -> dict[str, Any]:
    """The vcrpy cassette document of ``data`` (what :func:`encode` serialises), its digest
    still :data:`_UNSET`."""
    interactions = [
        _interaction(request, response)
        for request, response in zip(data.requests, data.responses, strict=True)
    ]
    emrd: dict[str, Any] = {"digest": _UNSET}
    if data.raw:
        emrd["raw"] = sorted(data.raw)
    emrd["protocol"] = data.protocol
    return {
        "interactions": interactions,
        "metadata": {"emrd": emrd},
        "version": CASSETTE_FORMAT_VERSION,
    }


def _digest(whole: bytes, recorded: str) -> str:
    """SHA-256 of the whole encoded document with its last ``recorded`` (the digest, in
    ``metadata``, which sorts after ``interactions``) read as :data:`_UNSET`. The document
    (a few MB) is hashed around ``recorded`` in place, not copied again."""
    mark = recorded.encode()
    at = whole.rfind(mark)
    if at < 0:
        return DIGEST_PREFIX + hashlib.sha256(whole).hexdigest()
    view = memoryview(whole)
    digest = hashlib.sha256(view[:at])
    digest.update(_UNSET.encode())
    digest.update(view[at + len(mark) :])
    return DIGEST_PREFIX + digest.hexdigest()


def encode(data: CassetteData) -> bytes:
    """The xz-compressed vcrpy JSON cassette of ``data`` (deterministic).

    :param data: The cassette.
    :returns: The file's bytes.
    """
    text = jsonserializer.serialize(document(data))
    head, _, tail = text.rpartition(_UNSET)
    text = head + _digest(text.encode(), _UNSET) + tail
    return lzma.compress(
        text.encode(), format=lzma.FORMAT_XZ, check=lzma.CHECK_CRC32, filters=_XZ_FILTERS
    )


def decompress(source: bytes | BinaryIO, *, cap: int = MAX_TEXT_BYTES) -> str:
    """The text inside ``source`` (bytes or a binary file), xz or gzip (told by the magic
    bytes), inflated a chunk at a time: more than ``cap`` bytes of text is a
    :class:`FormatError` before any more is inflated.

    :param source: Compressed bytes or a binary file.
    :param cap: Largest text accepted, in bytes.
    :returns: The decompressed text.
    """
    return inflated(source, cap=cap)[0]


def inflated(source: bytes | BinaryIO, *, cap: int = MAX_TEXT_BYTES) -> tuple[str, bytes]:
    """:func:`decompress`, and the text still encoded (what the digest covers)."""
    stream = io.BytesIO(source) if isinstance(source, bytes) else source
    pending = stream.read(_CHUNK)
    if pending.startswith(_XZ_MAGIC):
        inflater: Any = lzma.LZMADecompressor(lzma.FORMAT_XZ)
    elif pending.startswith(_GZIP_MAGIC):
        inflater = zlib.decompressobj(wbits=31)
    else:
        raise FormatError(f"not an xz- or gzip-compressed file (it starts {pending[:8]!r})")
    pieces: list[bytes] = []
    size = 0
    try:
        while not inflater.eof:
            piece = inflater.decompress(pending, cap + 1 - size)
            pieces.append(piece)
            size += len(piece)
            if size > cap:
                raise FormatError(
                    f"it inflates to more than {cap >> 20} MiB of text, more than a cassette "
                    "holds (a 50-step episode is a few MB); it is not a recording"
                )
            pending = getattr(inflater, "unconsumed_tail", b"")
            if not (pending or inflater.eof) and getattr(inflater, "needs_input", True):
                pending = stream.read(_CHUNK)
                if not (pending or piece):
                    raise EOFError("the compressed data ends early")
        whole = b"".join(pieces)
        return whole.decode(), whole
    except (EOFError, zlib.error, lzma.LZMAError, UnicodeDecodeError) as exc:
        raise FormatError(f"not a readable xz or gzip file ({exc})") from exc


def _field(at: str, value: Any, shape: Any) -> None:
    """:class:`FormatError` naming the first field of ``value`` that is not of ``shape``: a
    type or tuple of types, ``[shape]`` (a list of it), or a mapping of field -> shape (a
    name ending ``?`` is optional, ``*`` is every value; other fields are left open)."""
    kind = type(shape) if isinstance(shape, list | dict) else shape
    if not isinstance(value, kind) or isinstance(value, bool):
        wanted = _NAMES[getattr(kind, "__name__", "tuple")]
        raise FormatError(f"{at}={_brief(value)} is not {wanted}")
    if isinstance(shape, list):
        for index, item in enumerate(value):
            _field(f"{at}[{index}]", item, shape[0])
    for name, inner in shape.items() if isinstance(shape, dict) else ():
        key = name.rstrip("?")
        if name == "*":
            for each, item in value.items():
                _field(f"{at}.{each}", item, inner)
        elif key in value:
            _field(f"{at}.{key}", value[key], inner)
        elif key == name:
            raise FormatError(f"{at}.{name} is missing")


def _brief(value: Any) -> str:
    text = json.dumps(value) if isinstance(value, str | int | float | None) else None
    return text if text is not None and len(text) <= 40 else f"<{type(value).__name__}>"


_NAMES: Final = {
    "dict": "a mapping",
    "list": "a list",
    "str": "text",
    "int": "a whole number",
    "tuple": "text or null",
}
_TEXT: Final = (str, type(None))
#: What :func:`decode` needs of a document before it uses it (open to fields it does not read).
_SCHEMA: Final = {
    "interactions": [
        {
            "request": {"body": _TEXT, "headers": {"*": [str]}, "method": str, "uri": str},
            "response": {
                "body": {"string": _TEXT},
                "headers": {"*": [str]},
                "status": {"code": int, "message": str},
            },
        }
    ],
    "metadata": {"emrd": {"digest": str, "protocol": str, "raw?": [int]}},
}


def decode(blob: bytes) -> CassetteData:
    """:func:`parse` of the text :func:`decompress` finds in ``blob``.

    :param blob: A compressed cassette file's bytes.
    :returns: The parsed :class:`CassetteData`.
    """
    return parse(*inflated(blob))


def parse(text: str, whole: bytes) -> CassetteData:
    """Inverse of :func:`encode` (after :func:`inflated`, ``whole`` being ``text`` encoded):
    :class:`LegacyFormatError` for a file an older release wrote, :class:`IntegrityError` when
    the file no longer matches its digest, :class:`FormatError` for anything else that is not
    a cassette (checked against :data:`_SCHEMA` before use)."""
    if text.startswith(LEGACY_HEAD):
        raise LegacyFormatError("its format is emrd-cassette/1 or /2")
    try:
        loaded = orjson.loads(whole)
    except ValueError as exc:
        raise FormatError(f"not valid JSON ({exc})") from None
    _field("cassette", loaded, _SCHEMA)
    emrd, interactions = loaded["metadata"]["emrd"], loaded["interactions"]
    if not emrd["digest"].startswith(DIGEST_PREFIX):
        raise LegacyFormatError("its digest covers its interactions only")
    if _digest(whole, emrd["digest"]) != emrd["digest"]:
        raise IntegrityError("its bytes do not match the digest recorded with them")
    requests = tuple(
        Request(r["method"], r["uri"], r["body"], r["headers"])
        for r in (item["request"] for item in interactions)
    )
    responses = tuple(compat.convert_to_bytes(item["response"]) for item in interactions)
    return CassetteData(emrd["protocol"], requests, responses, frozenset(emrd.get("raw", ())))
