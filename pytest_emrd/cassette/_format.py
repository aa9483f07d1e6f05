"""The cassette file format: content-addressed YAML inside gzip (pure encode/decode).

A model request repeats the whole history window every step (system prompt + the last ten
turns), so a plain cassette stores every message up to 20 times. Here each distinct string
is stored once, in a table, and interactions refer to it by index:

.. code-block:: yaml

    format: emrd-cassette/1
    protocol: "w3+p2"              # world + prompt protocol the traffic was recorded under
    strings:                       # every distinct message / body part / response body, once
      - '{"content":"You are ...","role":"system"}'
      - ...
    interactions:
      - request:
          method: POST
          uri: http://127.0.0.1:8123/v1/chat/completions
          headers: {Content-Type: application/json}
          body: {lists: {messages: [0, 3, 4]}, rest: 2}   # or {raw: 7} when not JSON
        response:
          status: {code: 200, message: OK}
          headers: {content-type: [application/json]}
          body: 5

Request bodies are stored already redacted and canonical (see :mod:`._redact`): each
top-level list of the JSON body (``messages``, ``contents``...) is split into its items, the
rest of the object is one more string. Loading rebuilds the canonical bytes exactly, because
canonical JSON is a fixed point of parse + serialise. Gzip runs with ``mtime=0`` so the same
traffic always gives the same file bytes.
"""

from __future__ import annotations

import base64
import gzip
import json
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

import yaml
from vcr.request import Request

from pytest_emrd.cassette._redact import canonical_json

FORMAT: Final = "emrd-cassette/1"
_B64: Final = "base64:"

_Dumper = getattr(yaml, "CSafeDumper", yaml.SafeDumper)
_Loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class FormatError(ValueError):
    """The bytes are not an EMRD cassette; the message says which part is wrong."""


@dataclass(frozen=True)
class CassetteData:
    """Everything one cassette file holds."""

    protocol: str
    requests: tuple[Request, ...]
    responses: tuple[dict[str, Any], ...]


class _Table:
    def __init__(self) -> None:
        self.strings: list[str] = []
        self._index: dict[str, int] = {}

    def intern(self, text: str) -> int:
        index = self._index.get(text)
        if index is None:
            index = self._index[text] = len(self.strings)
            self.strings.append(text)
        return index


def _text(data: bytes | str | None) -> str:
    raw = data.encode() if isinstance(data, str) else (data or b"")
    try:
        return raw.decode()
    except UnicodeDecodeError:
        return _B64 + base64.b64encode(raw).decode()


def _bytes(text: str) -> bytes:
    if text.startswith(_B64):
        return base64.b64decode(text[len(_B64) :])
    return text.encode()


def _encode_body(body: bytes | str | None, table: _Table) -> dict[str, Any]:
    raw = body.encode() if isinstance(body, str) else (body or b"")
    try:
        tree = json.loads(raw)
    except (ValueError, UnicodeDecodeError):
        tree = None
    if not isinstance(tree, dict) or canonical_json(tree).encode() != raw:
        return {"raw": table.intern(_text(raw))}
    lists = {
        k: [table.intern(canonical_json(v)) for v in tree[k]]
        for k in sorted(tree)
        if isinstance(tree[k], list)
    }
    rest = {k: v for k, v in tree.items() if k not in lists}
    return {"lists": lists, "rest": table.intern(canonical_json(rest))}


def _decode_body(body: dict[str, Any], strings: Sequence[str]) -> bytes:
    if "raw" in body:
        return _bytes(strings[body["raw"]])
    tree = json.loads(strings[body["rest"]])
    for key, refs in body["lists"].items():
        tree[key] = [json.loads(strings[i]) for i in refs]
    return canonical_json(tree).encode()


def encode(data: CassetteData) -> bytes:
    """Gzip-compressed YAML bytes of ``data`` (deterministic)."""
    table = _Table()
    interactions = []
    for request, response in zip(data.requests, data.responses, strict=True):
        interactions.append(
            {
                "request": {
                    "method": request.method,
                    "uri": request.uri,
                    "headers": dict(request.headers),
                    "body": _encode_body(request.body, table),
                },
                "response": {
                    "status": dict(response["status"]),
                    "headers": {k: list(v) for k, v in response["headers"].items()},
                    "body": table.intern(_text(response["body"]["string"])),
                },
            }
        )
    document = {
        "format": FORMAT,
        "protocol": data.protocol,
        "strings": table.strings,
        "interactions": interactions,
    }
    text = yaml.dump(document, Dumper=_Dumper, sort_keys=False, allow_unicode=True, width=1 << 30)
    return gzip.compress(text.encode(), compresslevel=9, mtime=0)


def decode(blob: bytes) -> CassetteData:
    """Inverse of :func:`encode`; :class:`FormatError` says what is wrong with ``blob``."""
    try:
        text = gzip.decompress(blob).decode()
    except (OSError, EOFError, zlib.error, UnicodeDecodeError) as exc:
        raise FormatError(f"not a gzip-compressed text file ({exc})") from exc
    try:
        document = yaml.load(text, Loader=_Loader)
    except yaml.YAMLError as exc:
        raise FormatError(f"not valid YAML ({exc})") from exc
    if not isinstance(document, dict) or document.get("format") != FORMAT:
        found = document.get("format") if isinstance(document, dict) else type(document).__name__
        raise FormatError(f"format={found!r} is not {FORMAT!r}")
    try:
        strings = document["strings"]
        requests, responses = [], []
        for item in document["interactions"]:
            req, resp = item["request"], item["response"]
            requests.append(
                Request(
                    req["method"], req["uri"], _decode_body(req["body"], strings), req["headers"]
                )
            )
            responses.append(
                {
                    "status": resp["status"],
                    "headers": resp["headers"],
                    "body": {"string": _bytes(strings[resp["body"]])},
                }
            )
        return CassetteData(str(document["protocol"]), tuple(requests), tuple(responses))
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise FormatError(f"malformed interaction ({type(exc).__name__}: {exc})") from exc
