"""Reading the user's YAML files (thresholds, model registry): one-line errors, YAML 1.2 floats.

Every failure (missing file, directory, unreadable, not UTF-8, malformed YAML) is a one-line
:class:`~pytest_emrd.errors.ConfigError` naming the file, the line where there is one, and
what to do. Files are bounded and plain: larger than :data:`MAX_FILE_BYTES`, any YAML alias
(a few nested ones expand a small file into gigabytes), any explicit tag, a duplicate key and
nesting deeper than :data:`MAX_DEPTH` are refused before anything is composed.
:class:`Loader` adds the YAML 1.2 core-schema float (PyYAML's 1.1 reads ``1e9`` as a
string), so every number a person writes reads as a number.
"""

from __future__ import annotations

import re
from pathlib import Path
from typing import Any, Final

import yaml

from pytest_emrd.errors import ConfigError

#: Largest user YAML file read (a thresholds file or registry is a few kilobytes).
MAX_FILE_BYTES: Final = 1_000_000
#: Deepest nesting of collections accepted in a user YAML file.
MAX_DEPTH: Final = 32
_STD: Final = "tag:yaml.org,2002:"

_FLOAT_12 = re.compile(
    r"""^(?:[-+]?(?:\.[0-9]+|[0-9]+(?:\.[0-9]*)?)(?:[eE][-+]?[0-9]+)?
    |[-+]?\.(?:inf|Inf|INF)
    |\.(?:nan|NaN|NAN))$""",
    re.VERBOSE,
)


class Loader(yaml.SafeLoader):
    """PyYAML's safe loader with YAML 1.2 floats (``1e9``, ``5E-3``) resolved as floats."""


class _FastLoader(getattr(yaml, "CSafeLoader", yaml.SafeLoader)):  # type: ignore[misc]
    """:class:`Loader` on libyaml when PyYAML has it (15x faster on the thresholds file every
    pytest process reads); a file it rejects is parsed again by :class:`Loader`, whose
    error message is the one reported."""


for _loader in (Loader, _FastLoader):
    _loader.add_implicit_resolver(
        "tag:yaml.org,2002:float", _FLOAT_12, list("-+0123456789.")
    )  # checked after the 1.1 resolvers: ints stay ints


def read_text(path: Path, *, what: str, flag: str) -> str:
    """The UTF-8 text of ``path`` (``what`` = "thresholds file"; ``flag`` = the option that
    names it), or a one-line :class:`ConfigError` saying what is wrong and what to pass."""
    try:
        with Path(path).open("rb") as handle:
            data = handle.read(MAX_FILE_BYTES + 1)
    except FileNotFoundError:
        raise ConfigError(
            f"{what} {path} does not exist; pass an existing file with {flag}."
        ) from None
    except IsADirectoryError:
        raise ConfigError(
            f"{what} {path} is a directory, not a file; pass the YAML file itself with {flag}."
        ) from None
    except OSError as exc:
        raise ConfigError(f"{what} {path} cannot be read ({exc.strerror}); check {flag}.") from None
    if len(data) > MAX_FILE_BYTES:
        raise ConfigError(
            f"{what} {path} is larger than {MAX_FILE_BYTES // 1000} KB, more than such a file "
            f"ever needs; pass the right file with {flag}."
        )
    try:
        return data.decode("utf-8")
    except UnicodeDecodeError as exc:
        line = data.count(b"\n", 0, exc.start) + 1
        raise ConfigError(
            f"{what} {path}, line {line}: byte 0x{data[exc.start]:02x} at offset {exc.start} is "
            f"not UTF-8; save the file as UTF-8 text (a YAML file, not a binary), or pass "
            f"another one with {flag}."
        ) from None


def yaml_error(exc: yaml.YAMLError, source: str) -> ConfigError:
    """The one-line error for malformed YAML: file, line and column, and PyYAML's problem."""
    mark = getattr(exc, "problem_mark", None) or getattr(exc, "context_mark", None)
    where = f", line {mark.line + 1}, column {mark.column + 1}" if mark is not None else ""
    problem = getattr(exc, "problem", None) or type(exc).__name__
    context = getattr(exc, "context", None)
    detail = f"{context}: {problem}" if context else problem
    return ConfigError(f"{source}{where}: malformed YAML ({' '.join(str(detail).split())}).")


def _check_bounds(text: str, source: str) -> None:
    """A one-line :class:`ConfigError` at the first alias, explicit tag (``!foo``,
    ``!!python/object/apply``, ``!!binary``: a file holds plain data), duplicate key, or
    collection nested deeper than :data:`MAX_DEPTH` of ``text`` (libyaml's composer recurses
    in C: 100,000 ``[`` crash the interpreter), found by a streaming parse; malformed YAML is
    left to the parser."""
    open_: list[list[Any]] = []  # per open collection: [keys seen (None: a list), nodes]
    try:
        for event in yaml.parse(text, Loader=_FastLoader):
            line = event.start_mark.line + 1
            if isinstance(event, yaml.NodeEvent) and open_ and open_[-1][0] is not None:
                keys, open_[-1][1] = open_[-1][0], open_[-1][1] + 1
                value = getattr(event, "value", None)
                if open_[-1][1] % 2 and isinstance(value, str):
                    if value in keys:
                        raise ConfigError(
                            f"{source}, line {line}: {value!r} appears twice in one mapping "
                            "(the last would win unseen); keep one."
                        )
                    keys.add(value)
            if isinstance(event, yaml.AliasEvent):
                raise ConfigError(
                    f"{source}, line {line}: YAML alias *{event.anchor} "
                    "is not allowed in this file (aliases can expand a small file without "
                    "bound); write the value out in full."
                )
            if getattr(event, "tag", None) is not None and not _implicit(event):
                raise ConfigError(
                    f"{source}, line {line}: YAML tag {event.tag.replace(_STD, '!!')} is not "
                    "allowed in this file (it holds plain data); remove the tag and write the "
                    "value itself."
                )
            if isinstance(event, yaml.CollectionStartEvent):
                open_.append([set() if isinstance(event, yaml.MappingStartEvent) else None, 0])
                if len(open_) > MAX_DEPTH:
                    raise _too_deep(source, line)
            elif isinstance(event, yaml.CollectionEndEvent):
                open_.pop()
    except yaml.YAMLError as exc:
        # libyaml >= 0.2.6 stops at its own nesting limit before our count reaches it
        if "nesting depth" in str(exc):
            mark = getattr(exc, "problem_mark", None)
            raise _too_deep(source, mark.line + 1 if mark else None) from None
        return


def _implicit(event: Any) -> bool:
    """Whether the tag of ``event`` is one the parser resolved itself, not one written out."""
    implicit = getattr(event, "implicit", False)
    return any(implicit) if isinstance(implicit, tuple) else bool(implicit)


def _too_deep(source: str, line: int | None) -> ConfigError:
    where = f"{source}, line {line}" if line is not None else source
    return ConfigError(
        f"{where}: YAML nested more than {MAX_DEPTH} levels deep; flatten it (a thresholds file "
        "or model registry needs five levels)."
    )


def _parsed(parse: Any, text: str, source: str) -> Any:
    _check_bounds(text, source)
    try:
        return parse(text, Loader=_FastLoader)
    except yaml.YAMLError:
        pass
    try:
        return parse(text, Loader=Loader)
    except yaml.YAMLError as exc:
        raise yaml_error(exc, source) from None


def compose(text: str, source: str) -> yaml.Node | None:
    """The YAML node tree of ``text`` (with line marks), or a one-line :class:`ConfigError`."""
    return _parsed(yaml.compose, text, source)  # type: ignore[no-any-return]


def load(text: str, source: str) -> Any:
    """``text`` as Python data (YAML 1.2 floats), or a one-line :class:`ConfigError`."""
    return _parsed(yaml.load, text, source)


def scalar(node: yaml.Node) -> Any:
    """The Python value of a scalar node, resolved like :func:`load` would."""
    return Loader("").construct_object(node, deep=True)


def describe(node: yaml.Node) -> str:
    """How a node reads in a message: the scalar as written, else its kind (never a repr)."""
    if isinstance(node, yaml.ScalarNode):
        return repr(node.value)
    return "a mapping" if isinstance(node, yaml.MappingNode) else "a list"
