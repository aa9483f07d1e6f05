"""Texts a cassette names instead of storing them: what pytest-emrd itself ships.

Every request of every episode carries the same system prompt (3.4 KB, the building overview
and the rules). Stored in each cassette it was a quarter of the compressed file: deflate or
LZMA cannot share bytes across files. So pytest-emrd ships the texts it writes into every
cassette, once, in ``shared_texts.json`` (a map from :func:`text_id` to text), and a
cassette's string table (format ``emrd-cassette/2``, see :mod:`._format`) may hold an
entry that rebuilds a string from one of them by an edit script:

.. code-block:: yaml

    - {from: 5b7f0e2cbe8d3b91, edit: [0, 3431]}             # the shipped text, verbatim
    - {from: 5b7f0e2cbe8d3b91, edit: [0, 1800, "Room A", 1810, 1621]}   # a variant of it

An edit script is a flat list read left to right: two integers ``start, length`` copy
``base[start:start + length]``, a string is inserted as it is. A prompt of another variant,
modality or layout is the shipped text with a few edits, so it costs tens of bytes too.

The file only ever grows (a text is added when the prompt changes, none is removed): a
cassette names a text by its content hash, so every cassette any release wrote stays
readable by every later release. A cassette naming a text this release does not ship was
written by a newer pytest-emrd, and reading it says so.
"""

from __future__ import annotations

import difflib
import functools
import hashlib
import json
import lzma
import re
from collections.abc import Sequence
from pathlib import Path
from typing import Any, Final

#: The texts pytest-emrd ships for cassettes to name (package data).
SHARED_FILE: Final = Path(__file__).with_name("shared_texts.json")
#: Strings shorter than this are stored as they are (an edit script would not pay).
_MIN_LENGTH: Final = 512
#: A copy shorter than this is inserted instead (a copy costs two numbers in the file).
_MIN_COPY: Final = 16
#: A text is compared with a shipped one only if it contains at least two of the eight
#: evenly spaced 24-character samples of it (a cheap test that skips unrelated strings).
_SAMPLES: Final = 8
_SAMPLE_LENGTH: Final = 24
#: Word, run of spaces or single other character: the units :func:`edit_script` aligns.
_TOKEN: Final = re.compile(r"\w+|\s+|[^\w\s]")

Edit = list[int | str]


def text_id(text: str) -> str:
    """The name of ``text`` in ``shared_texts.json``: its SHA-256, first 16 hex digits."""
    return hashlib.sha256(text.encode()).hexdigest()[:16]


@functools.cache
def shared_texts() -> dict[str, str]:
    """The shipped texts by :func:`text_id` (read once per process)."""
    return json.loads(SHARED_FILE.read_text(encoding="utf-8"))


@functools.cache
def _samples(base: str) -> tuple[str, ...]:
    step = max(1, (len(base) - _SAMPLE_LENGTH) // _SAMPLES)
    return tuple(base[i : i + _SAMPLE_LENGTH] for i in range(0, step * _SAMPLES, step))


def _resembles(text: str, base: str) -> bool:
    return sum(sample in text for sample in _samples(base)) >= 2


def shipped_bytes() -> int:
    """The size of ``shared_texts.json`` compressed as a cassette is (what shipping the texts
    costs, to count once beside the cassettes that name them)."""
    return len(lzma.compress(SHARED_FILE.read_bytes(), format=lzma.FORMAT_XZ, preset=9))


def edit_script(text: str, base: str) -> Edit:
    """A flat edit script that rebuilds ``text`` from ``base`` (see the module docstring).

    Words are aligned with :class:`difflib.SequenceMatcher` (no junk heuristic, so the result
    depends on the two texts only); copies shorter than 16 characters become inserts, and
    neighbouring inserts are joined.
    """
    old, new = _TOKEN.findall(base), _TOKEN.findall(text)
    starts = [0]
    for token in old:
        starts.append(starts[-1] + len(token))
    script: Edit = []
    pending: list[str] = []
    matcher = difflib.SequenceMatcher(None, old, new, autojunk=False)
    for tag, i1, i2, j1, j2 in matcher.get_opcodes():
        length = starts[i2] - starts[i1]
        if tag != "equal" or length < _MIN_COPY:
            pending.extend(new[j1:j2])
            continue
        if pending:
            script.append("".join(pending))
            pending = []
        script += [starts[i1], length]
    if pending:
        script.append("".join(pending))
    return script


def apply_edit(base: str, script: Sequence[int | str]) -> str:
    """The text ``script`` builds from ``base``; :class:`ValueError` if it is not a script."""
    parts: list[str] = []
    k = 0
    while k < len(script):
        op = script[k]
        if isinstance(op, str):
            parts.append(op)
            k += 1
            continue
        length = script[k + 1] if k + 1 < len(script) else None
        if type(op) is not int or type(length) is not int or op < 0 or length < 0:
            raise ValueError(f"edit script item {k} is not a string or two integers >= 0")
        if op + length > len(base):
            raise ValueError(f"edit script copies [{op}, {op + length}) of a {len(base)}-char text")
        parts.append(base[op : op + length])
        k += 2
    return "".join(parts)


def _cost(script: Edit) -> int:
    return sum(len(op) if isinstance(op, str) else 5 for op in script)


@functools.lru_cache(maxsize=32)
def _script(text: str, base: str) -> Edit:
    """:func:`edit_script`, once per text and base in a process: every cassette of a run under
    one variant, modality and step budget carries the same system prompt, and aligning it
    with the shipped one takes tens of milliseconds, holding the GIL that concurrent episodes
    (``--emrd-concurrency``) share."""
    return [0, len(base)] if text == base else edit_script(text, base)


def pack(text: str) -> str | dict[str, Any]:
    """``text``, or the entry naming the shipped text it is (nearly) a copy of.

    A shipped text is used when the edit script costs less than a third of ``text``; the
    candidates are the shipped texts of comparable length (half to twice as long) that share
    at least two of eight sampled passages with it.
    """
    if len(text) < _MIN_LENGTH:
        return text
    best: tuple[int, str, Edit] | None = None
    for name, base in shared_texts().items():
        if not len(base) // 2 <= len(text) <= 2 * len(base) or not _resembles(text, base):
            continue
        script = list(_script(text, base))
        cost = _cost(script)
        if cost * 3 < len(text) and (best is None or cost < best[0]):
            best = (cost, name, script)
    return text if best is None else {"from": best[1], "edit": best[2]}


class NewerTextError(ValueError):
    """A cassette names a shipped text this pytest-emrd does not have."""


def unpack(entry: str | dict[str, Any]) -> str:
    """Inverse of :func:`pack`; :class:`ValueError` for an entry that is neither form."""
    if type(entry) is str:
        return entry
    if not isinstance(entry, dict) or set(entry) != {"from", "edit"}:
        raise ValueError(f"string table entry {entry!r:.80} is not a string or {{from, edit}}")
    base = shared_texts().get(entry["from"])
    if base is None:
        raise NewerTextError(
            f"it names the shipped text {entry['from']!r}, which this pytest-emrd does not "
            "have: it was written by a newer pytest-emrd"
        )
    return apply_edit(base, entry["edit"])
