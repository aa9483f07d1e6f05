"""``emrd cassettes upgrade``: convert the cassettes older releases wrote, once, verified.

Formats ``emrd-cassette/1`` (``ep<NN>.yaml.gz``) and ``/2`` (``.yaml.xz``; a string may be an
edit ``{from: <id>, edit: [start, length, "inserted", ...]}`` of a shipped text,
``legacy_texts.json``) hold tables of strings and messages the bodies refer to. Each body is
rebuilt byte for byte; the new file is kept only if it reads back to the same protocol and
interactions, then the old one is removed."""

from __future__ import annotations

import base64
import functools
import json
from collections.abc import Iterator, Sequence
from dataclasses import dataclass
from pathlib import Path
from typing import Any, Final

from vcr.request import Request

from pytest_emrd._atomic import write_bytes_atomic
from pytest_emrd._wire import encoder
from pytest_emrd.cassette._file import SUFFIX, CassetteData, decode, decompress, encode
from pytest_emrd.cassette._paths import LEGACY_SUFFIXES, SCRATCH, scratch_path
from pytest_emrd.cassette._redact import canonical_json
from pytest_emrd.errors import CassetteError

FORMATS: Final = ("emrd-cassette/1", "emrd-cassette/2")  # see _file.LEGACY_HEAD
_TEXTS: Final = Path(__file__).with_name("legacy_texts.json")
_SERIALISE: Final = {
    "canonical": canonical_json,
    "compact": encoder(sort_keys=False, ensure_ascii=False),
    "ascii": encoder(sort_keys=False, ensure_ascii=True),
}
_B64: Final = "base64:"
_REF: Final = "\x00"


class LegacyError(ValueError):
    """The bytes are not a cassette of format 1 or 2; the message says what is wrong."""


@functools.cache
def _shipped() -> dict[str, str]:
    return json.loads(_TEXTS.read_text(encoding="utf-8"))


def _apply_edit(base: str, script: Sequence[int | str]) -> str:
    """The text an edit script builds: a string is inserted, ``start, length`` copies."""
    parts, k = [], 0
    while k < len(script):
        if isinstance(script[k], str):
            parts.append(script[k])
            k += 1
        else:
            start, length = int(script[k]), int(script[k + 1])
            parts.append(base[start : start + length])
            k += 2
    return "".join(str(p) for p in parts)


def _string(entry: str | dict[str, Any]) -> str:
    if isinstance(entry, str):
        return entry
    base = _shipped().get(entry["from"])
    if base is None:
        raise LegacyError(f"it names the shipped text {entry['from']!r}, which is unknown")
    return _apply_edit(base, entry["edit"])


def _unpack(node: Any, strings: Sequence[str]) -> Any:
    if isinstance(node, str):
        return strings[int(node[1:])] if node.startswith(_REF) else node
    if isinstance(node, dict):
        return {k: _unpack(v, strings) for k, v in node.items()}
    if isinstance(node, list):
        return [_unpack(v, strings) for v in node]
    return node


def _body(body: dict[str, Any], strings: Sequence[str], templates: Sequence[str]) -> bytes:
    if "raw" in body:
        text = strings[body["raw"]]
        if text.startswith(_B64):
            return base64.b64decode(text[len(_B64) :])
        return text.encode()
    tree = _unpack(json.loads(body["json"]), strings)
    for key, runs in body.get("lists", {}).items():
        tree[key] = [
            _unpack(json.loads(templates[start + k]), strings)
            for start, length in runs
            for k in range(length)
        ]
    return _SERIALISE[body["mode"]](tree).encode()


def read_legacy(blob: bytes) -> CassetteData:
    """Everything a format-1 or format-2 cassette holds (:class:`LegacyError` if it is not one)."""
    try:
        document = json.loads(decompress(blob))
        if document.get("format") not in FORMATS:
            raise LegacyError(f"format={document.get('format')!r} is not {' or '.join(FORMATS)}")
        strings = [_string(entry) for entry in document["strings"]]
        templates = document["templates"]
        requests, responses, raw = [], [], []
        for index, item in enumerate(document["interactions"]):
            req, resp = item["request"], item["response"]
            body = _body(req["body"], strings, templates)
            requests.append(Request(req["method"], req["uri"], body, req["headers"]))
            if req["body"].get("mode") != "canonical":
                raw.append(index)
            reply = {"string": _body(resp["body"], strings, templates)}
            responses.append({"status": resp["status"], "headers": resp["headers"], "body": reply})
    except LegacyError:
        raise
    except (KeyError, IndexError, TypeError, ValueError, AttributeError) as exc:
        raise LegacyError(f"malformed document ({type(exc).__name__}: {exc})") from exc
    return CassetteData(
        str(document["protocol"]), tuple(requests), tuple(responses), frozenset(raw)
    )


@dataclass(frozen=True)
class Upgraded:
    """One cassette converted: where it was and is, and its size before and after."""

    old: Path
    new: Path
    old_bytes: int
    new_bytes: int


def upgrade(root: Path) -> Iterator[Upgraded]:
    """Convert every old cassette under ``root`` (not in its scratch folder), one at a time: an
    interrupted run leaves no half-written file, and running it again goes on. A
    :class:`CassetteError` names a file that is not an old cassette or whose new twin exists."""
    found = (p for suffix in LEGACY_SUFFIXES for p in root.rglob(f"*{suffix}"))
    for old in sorted(p for p in found if SCRATCH not in p.relative_to(root).parts):
        new = old.with_name(old.name[: -len(".yaml.gz")] + SUFFIX)
        if new.exists():
            raise CassetteError(
                f"cassette={str(old)!r} has a twin {new.name} already, which replays instead; "
                "delete the one you do not want and run the upgrade again"
            )
        blob = old.read_bytes()
        try:
            data = read_legacy(blob)
        except LegacyError as exc:
            raise CassetteError(f"cassette={str(old)!r} is not an old cassette: {exc}") from None
        rewritten = encode(data)
        if not same_interactions(decode(rewritten), data):  # a bug must never lose traffic
            raise CassetteError(f"cassette={str(old)!r} did not survive conversion; kept as is")
        write_bytes_atomic(new, rewritten, temp=scratch_path(root, new, ""))
        old.unlink()
        yield Upgraded(old, new, len(blob), len(rewritten))


def same_interactions(a: CassetteData, b: CassetteData) -> bool:
    """Whether two cassettes hold the same protocol and interactions, byte for byte."""

    def held(data: CassetteData) -> tuple[Any, ...]:
        requests = [(r.method, r.uri, r.body, sorted(r.headers.items())) for r in data.requests]
        return data.protocol, requests, list(data.responses)

    return held(a) == held(b)
