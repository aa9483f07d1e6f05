"""The cassette file format: content-addressed YAML inside xz (pure encode/decode).

(The layout below is shown in block style for reading; files are written in YAML's
JSON-compatible flow style, see :func:`encode`.)

A model request repeats the whole history window every step (system prompt + the last ten
turns), and each reply comes back once as a response and then up to ten times inside later
requests. So the file holds a table of distinct strings and everything else refers to it:

.. code-block:: yaml

    format: emrd-cassette/2
    protocol: "builtin-4+p2"       # world + prompt protocol the traffic was recorded under
    strings:                       # each distinct long string once (reply, user text, digest)
      - "pixels:24bcfde163e2140cffae7feb506edf907154d0cab0aab706b4487f4a0fcd5519"
      - '{"observation":"8 objects in view.","dedup_check":"8 new, 0 already mapped.",...}'
      - {from: cebd7bac61aaf8a8, edit: [0, 3431]}   # the system prompt, which pytest-emrd ships
      - ...
    templates:                     # each distinct message once; "\u0000N" = strings[N]
      - '{"content":"\\u00002","role":"system"}'
      - ...
    interactions:
      - request:
          method: POST
          uri: http://127.0.0.1:8123/v1/chat/completions
          headers: {content-type: application/json}
          body:                    # or {raw: 7} when the body is not JSON
            json: '{"messages":null,"model":"scout","temperature":0.0}'   # the skeleton
            lists: {messages: [[0, 1], [5, 20]]}   # template runs (start, length)
            mode: canonical        # re-serialisation: canonical | compact | ascii
        response:
          status: {code: 200, message: OK}
          headers: {content-type: [application/json]}
          body: {json: '{"choices":[{"message":{"content":"\\u00001"}}]}', mode: compact}

Request bodies are stored already redacted and canonical (see :mod:`._redact`): each item of
a top-level list (``messages``, ``contents``...) is one template, so a message repeated
across requests is stored once, and a history window is a few runs of template indices.
Inside templates and response bodies every string of 48 characters or more is replaced by
a reference (NUL + index into ``strings``), so a reply text is stored once for its response
and for all the requests that carry it back. Loading rebuilds the canonical bytes
exactly (canonical JSON is a fixed point of parse + serialise); a JSON response is stored as
a tree only when compact serialisation reproduces its bytes exactly, else verbatim.

A string of the table is either the string or ``{from, edit}``: an edit script over a text
pytest-emrd ships (:mod:`._shared`), which is how the 3.4 KB system prompt every cassette
carries costs a few bytes. The document is compressed with xz (LZMA2, 1 MiB dictionary,
CRC32 check, no timestamp), so the same traffic always gives the same file bytes and
``xz -dc ep00.yaml.xz`` shows it.

Format ``emrd-cassette/1`` (files ``.yaml.gz``, written before) is the same document without
``{from, edit}`` entries, in gzip: :func:`decode` reads both, telling the container by its
magic bytes. Against format 1 the 320 committed cassettes shrank from 2.99 MB to 1.88 MB
(-37 %); on the 24 of ``replay.size_ratio_vs_plain_vcrpy``, xz alone gives -13.5 % and naming
the system prompt 21 points more (-34.7 %). Storing each reply as an edit of the previous
one, the obvious next step, was measured and rejected: LZMA2 already finds those copies
across the whole file, and an edit script's numbers cost more than its matches (+8.6 %).
"""

from __future__ import annotations

import base64
import gzip
import json
import lzma
import re
import zlib
from collections.abc import Sequence
from dataclasses import dataclass
from typing import Any, Final

import yaml
from vcr.request import Request

from pytest_emrd._wire import encoder, key_json, splice
from pytest_emrd.cassette._redact import DIGEST, canonical_json
from pytest_emrd.cassette._shared import NewerTextError, pack, unpack
from pytest_emrd.errors import CassetteError

FORMAT: Final = "emrd-cassette/2"
#: What :func:`encode` wrote before (gzip, every string stored): still read.
LEGACY_FORMAT: Final = "emrd-cassette/1"
_FAMILY: Final = "emrd-cassette/"
_XZ_MAGIC: Final = b"\xfd7zXZ\x00"
_GZIP_MAGIC: Final = b"\x1f\x8b"
#: LZMA2 at its strongest setting, with no 4-byte alignment assumed (``pb=0``: the document
#: is text); a 1 MiB dictionary holds a whole cassette (the largest committed one is 0.4 MB of
#: text) and keeps the reader's buffer small.
_XZ_FILTERS: Final = (
    {"id": lzma.FILTER_LZMA2, "preset": 9 | lzma.PRESET_EXTREME, "dict_size": 1 << 20, "pb": 0},
)
_B64: Final = "base64:"
_REF: Final = "\x00"
#: Strings at least this long are stored once in the table and referenced from the trees.
_LONG: Final = 48

_Loader = getattr(yaml, "CSafeLoader", yaml.SafeLoader)


class FormatError(ValueError):
    """The bytes are not an EMRD cassette; the message says which part is wrong."""


class NewerFormatError(FormatError, CassetteError):
    """An EMRD cassette written by a newer pytest-emrd: a later format, or a shipped text
    (:mod:`._shared`) this release does not have."""


@dataclass(frozen=True)
class CassetteData:
    """Everything one cassette file holds."""

    protocol: str
    requests: tuple[Request, ...]
    responses: tuple[dict[str, Any], ...]
    canonical: tuple[bool, ...] = ()
    """Per request, read back: its body is canonical JSON (a recorded, redacted request)."""


class _Table:
    def __init__(self, seed: Sequence[str] = ()) -> None:
        self.strings: list[str] = list(seed)
        self._index: dict[str, int] = {text: i for i, text in enumerate(self.strings)}

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


def _compact(tree: Any, ascii_only: bool) -> str:
    return _SERIALISE["ascii" if ascii_only else "compact"](tree)


def _pack(node: Any, table: _Table) -> Any:
    """Replace every long string (and any string starting with NUL) by a table reference."""
    if isinstance(node, dict):
        return {k: _pack(v, table) for k, v in node.items()}
    if isinstance(node, list):
        return [_pack(v, table) for v in node]
    if isinstance(node, str) and (len(node) >= _LONG or node.startswith(_REF)):
        return f"{_REF}{table.intern(node)}"
    return node


def _unpack(node: Any, strings: Sequence[str]) -> Any:
    kind = type(node)  # exactly what json.loads builds
    if kind is str:
        return strings[int(node[1:])] if node.startswith(_REF) else node
    if kind is dict:
        return {k: _unpack(v, strings) for k, v in node.items()}
    if kind is list:
        return [_unpack(v, strings) for v in node]
    return node


#: How a JSON body is re-serialised on load: canonical (requests) or compact as received.
_SERIALISE: Final = {
    "canonical": canonical_json,
    "compact": encoder(sort_keys=False, ensure_ascii=False),
    "ascii": encoder(sort_keys=False, ensure_ascii=True),
}


def _runs(indices: Sequence[int]) -> list[list[int]]:
    """``[0, 5, 6, 7]`` -> ``[[0, 1], [5, 3]]`` (start, length): a history window is a run."""
    runs: list[list[int]] = []
    for i in indices:
        if runs and runs[-1][0] + runs[-1][1] == i:
            runs[-1][1] += 1
        else:
            runs.append([i, 1])
    return runs


def _expand(runs: Sequence[Sequence[int]]) -> list[int]:
    return [start + k for start, length in runs for k in range(length)]


def _encode_body(
    body: bytes | str | None, table: _Table, templates: _Table | None
) -> dict[str, Any]:
    """A JSON body as a packed tree when it re-serialises byte for byte, else verbatim.

    With ``templates`` (request bodies), each item of a top-level list of a JSON object
    (``messages``, ``contents``...) is interned there as one template, so a message
    repeated across requests is stored once and a window is a few runs of indices.
    """
    raw = body.encode() if isinstance(body, str) else (body or b"")
    try:
        tree = json.loads(raw)
    except (ValueError, UnicodeDecodeError):
        return {"raw": table.intern(_text(raw))}
    for mode, serialise in _SERIALISE.items():
        if serialise(tree).encode() != raw:
            continue
        if not isinstance(tree, dict) or templates is None:
            return {"json": _compact(_pack(tree, table), False), "mode": mode}
        lists = {
            k: _runs([templates.intern(_compact(_pack(v, table), False)) for v in tree[k]])
            for k in tree
            if isinstance(tree[k], list)
        }
        rest = {k: (None if k in lists else v) for k, v in tree.items()}
        return {
            "json": _compact(_pack(rest, table), False),
            "lists": lists,
            "mode": mode,
        }
    return {"raw": table.intern(_text(raw))}


#: A table reference in a tree as :func:`encode` writes it (compact, ``ensure_ascii=False``): a
#: string *value* that is NUL and an index. A quote after a backslash is inside a string, and a
#: key is followed by ``:``; every other string starting with NUL is a reference (see _pack).
_REF_TEXT: Final = re.compile(r'(?<!\\)"\\u0000(\d+)"(?!:)')


class _Decoder:
    """Rebuilds bodies; each template is serialised once per mode, however many requests
    carry it (a message travels in up to ten consecutive windows).

    With ``verbatim`` (a file read as :func:`encode` wrote it), a tree to be written back
    compact or canonical is not parsed: its stored text is already that serialisation (the
    keys of a canonical body were sorted when it was stored), so each reference is replaced
    in the text by its string's JSON. Otherwise (a file edited into block-style YAML, or an
    ``ascii`` body) the tree is parsed, unpacked and serialised again.
    """

    def __init__(self, strings: Sequence[str], templates: Sequence[str], *, verbatim: bool) -> None:
        self.strings, self.templates, self.verbatim = strings, templates, verbatim
        self._items: dict[tuple[int, str], bytes] = {}
        self._refs: dict[str, str] = {}
        self._skeletons: dict[str, Any] = {}

    def _ref(self, ref: re.Match[str]) -> str:
        """The JSON of the string ``ref`` points to (a reply is referenced by its response
        and by the request that carries it back: escaped once)."""
        text = self._refs.get(ref[1])
        if text is None:
            text = self._refs[ref[1]] = key_json(self.strings[int(ref[1])], ensure_ascii=False)
        return text

    def _tree_text(self, text: str, mode: str) -> str:
        """``_SERIALISE[mode]`` of the stored tree ``text`` with its references resolved."""
        if self.verbatim and mode != "ascii":
            return _REF_TEXT.sub(self._ref, text)
        return _SERIALISE[mode](_unpack(json.loads(text), self.strings))

    def _item(self, index: int, mode: str) -> bytes:
        data = self._items.get((index, mode))
        if data is None:
            data = self._items[(index, mode)] = self._tree_text(
                self.templates[index], mode
            ).encode()
        return data

    def _skeleton(self, text: str) -> Any:
        """The stored tree ``text`` unpacked (every request of an episode has the same one)."""
        tree = self._skeletons.get(text)
        if tree is None:
            tree = self._skeletons[text] = _unpack(json.loads(text), self.strings)
        return tree

    def body(self, body: dict[str, Any]) -> tuple[bytes, bool]:
        """(body bytes, whether they are canonical JSON)."""
        if "raw" in body:
            return _bytes(self.strings[body["raw"]]), False
        mode = body["mode"]
        lists = body.get("lists", {})
        if not lists:
            return self._tree_text(body["json"], mode).encode(), mode == "canonical"
        # Each list spliced in from its items' UTF-8 serialisations (each template done once).
        serialise = _SERIALISE[mode]
        data = splice(
            {**self._skeleton(body["json"]), **{key: _expand(runs) for key, runs in lists.items()}},
            value=lambda value: serialise(value).encode(),
            item=lambda index: self._item(index, mode),
            sort_keys=mode == "canonical",
            ensure_ascii=mode == "ascii",
            binary=True,
        )
        return data, mode == "canonical"


def encode(data: CassetteData) -> bytes:
    """The xz-compressed YAML bytes of ``data`` in format ``emrd-cassette/2`` (deterministic).

    The YAML is written in its JSON-compatible flow style (JSON is a subset of YAML 1.2),
    which any YAML reader loads and which loads here at JSON speed; a cassette edited by
    hand into block-style YAML still loads (through PyYAML). The same traffic gives the same
    bytes (single-threaded LZMA2 with fixed settings, no timestamp in the container).
    """
    first = _Table()
    _interactions(data, first, _Table())
    # Second pass with the strings grouped by kind (frame digests, JSON texts such as replies,
    # other text), each group in order of first use: like sits next to like, which is what
    # the compressor's matching rewards. Same content, different indices.
    table, templates = _Table(sorted(first.strings, key=_kind)), _Table()
    interactions = _interactions(data, table, templates)
    document = {
        "format": FORMAT,
        "protocol": data.protocol,
        "strings": [pack(text) for text in table.strings],
        "templates": templates.strings,
        "interactions": interactions,
    }
    text = json.dumps(document, ensure_ascii=False, separators=(",", ":"))
    return lzma.compress(
        text.encode(), format=lzma.FORMAT_XZ, check=lzma.CHECK_CRC32, filters=_XZ_FILTERS
    )


def _kind(text: str) -> int:
    if DIGEST.match(text):
        return 0
    return 1 if text.startswith(("{", "[")) else 2


def _interactions(data: CassetteData, table: _Table, templates: _Table) -> list[dict[str, Any]]:
    interactions = []
    for request, response in zip(data.requests, data.responses, strict=True):
        interactions.append(
            {
                "request": {
                    "method": request.method,
                    "uri": request.uri,
                    "headers": dict(request.headers),
                    "body": _encode_body(request.body, table, templates),
                },
                "response": {
                    "status": dict(response["status"]),
                    "headers": {k: list(v) for k, v in response["headers"].items()},
                    "body": _encode_body(response["body"]["string"], table, None),
                },
            }
        )
    return interactions


def _text_of(blob: bytes) -> str:
    """The text inside ``blob``: xz (format 2) or gzip (format 1), told by the magic bytes."""
    try:
        if blob.startswith(_XZ_MAGIC):
            return lzma.decompress(blob, format=lzma.FORMAT_XZ).decode()
        if blob.startswith(_GZIP_MAGIC):
            return gzip.decompress(blob).decode()
    except (OSError, EOFError, zlib.error, lzma.LZMAError, UnicodeDecodeError) as exc:
        raise FormatError(f"not a readable xz or gzip file ({exc})") from exc
    raise FormatError(f"not an xz- or gzip-compressed text file (it starts {blob[:8]!r})")


def _document(blob: bytes) -> tuple[dict[str, Any], bool]:
    """The parsed document of ``blob`` (either format) and whether it is the flow-style text
    :func:`encode` writes (JSON), rather than YAML edited by hand."""
    text = _text_of(blob)
    try:
        document = json.loads(text)
    except ValueError:
        try:
            document = yaml.load(text, Loader=_Loader)
        except yaml.YAMLError as exc:
            raise FormatError(f"not valid YAML ({exc})") from exc
        verbatim = False
    else:
        verbatim = True
    found = document.get("format") if isinstance(document, dict) else type(document).__name__
    if found in (FORMAT, LEGACY_FORMAT):
        return document, verbatim
    readable = f"{LEGACY_FORMAT!r} or {FORMAT!r}"
    if isinstance(found, str) and found.startswith(_FAMILY):
        raise NewerFormatError(
            f"format={found!r} is newer than this pytest-emrd reads ({readable}): it was "
            "written by a newer pytest-emrd"
        )
    raise FormatError(f"format={found!r} is not {readable}")


def decode(blob: bytes) -> CassetteData:
    """Inverse of :func:`encode`, for both formats; :class:`FormatError` says what is wrong
    with ``blob`` (:class:`NewerFormatError` when a newer pytest-emrd wrote it)."""
    document, verbatim = _document(blob)
    try:
        strings = document["strings"]
        if document["format"] == FORMAT:
            strings = [unpack(entry) for entry in strings]
        decoder = _Decoder(strings, document["templates"], verbatim=verbatim)
        requests, responses, canonical = [], [], []
        for item in document["interactions"]:
            req, resp = item["request"], item["response"]
            body, is_canonical = decoder.body(req["body"])
            requests.append(Request(req["method"], req["uri"], body, req["headers"]))
            canonical.append(is_canonical)
            responses.append(
                {
                    "status": resp["status"],
                    "headers": resp["headers"],
                    "body": {"string": decoder.body(resp["body"])[0]},
                }
            )
        return CassetteData(
            str(document["protocol"]), tuple(requests), tuple(responses), tuple(canonical)
        )
    except NewerTextError as exc:
        raise NewerFormatError(str(exc)) from exc
    except (KeyError, IndexError, TypeError, ValueError) as exc:
        raise FormatError(f"malformed interaction ({type(exc).__name__}: {exc})") from exc
