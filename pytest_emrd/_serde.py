"""JSON round-trip for the frozen dataclasses that cross stage boundaries.

Field names are the file format: ``to_dict`` writes every field by name, ``from_dict``
rebuilds nested dataclasses and tuples from the type hints and rejects unknown keys so a
typo in a stored file is an error, never silently dropped data.
"""

from __future__ import annotations

import dataclasses
import math
import types
import typing
from collections.abc import Callable, Collection
from functools import cache
from typing import Any, ClassVar, Final, NamedTuple, Self, TypeVar

from pytest_emrd.errors import ProtocolError

T = TypeVar("T")


def to_dict(obj: Any) -> Any:
    """Plain JSON-able data (dicts, lists, str, numbers, None) from a dataclass tree.

    Dataclasses become dicts of their fields in declaration order, tuples and lists become
    lists, dict keys become ``str(key)``, sets become sorted lists; anything else (str, numbers
    including ``-0.0``/``nan``/``inf``, None, enums, paths) is returned as it is.
    """
    if isinstance(obj, _SCALARS):
        return obj
    names = _field_names(type(obj))
    if names is not None:
        return {name: to_dict(getattr(obj, name)) for name in names}
    if isinstance(obj, tuple | list):
        return [to_dict(v) for v in obj]
    if isinstance(obj, dict):
        return {str(k): to_dict(v) for k, v in obj.items()}
    if isinstance(obj, frozenset | set):
        return sorted(map(to_dict, obj))
    return obj


#: The classes JSON writes as scalars; :func:`to_dict` returns their values unchanged.
_SCALARS: Final = (str, int, float, type(None))


@cache
def _field_names(cls: type) -> tuple[str, ...] | None:
    """The field names of dataclass ``cls`` (read once per class), else None."""
    if dataclasses.is_dataclass(cls):
        return tuple(f.name for f in dataclasses.fields(cls))
    return None


def from_dict(cls: type[T], data: Any) -> T:
    """Rebuild ``cls`` from :func:`to_dict` output, validating keys on the way."""
    try:
        return _builder(cls)(data)  # type: ignore[no-any-return]
    except _Invalid as exc:
        raise ProtocolError(f"{cls.__name__}{exc.path}: {exc.message}") from exc.__cause__


class _Invalid(Exception):
    """A value that does not fit its type; ``path`` grows as the error climbs the tree."""

    def __init__(self, message: str) -> None:
        super().__init__(message)
        self.message, self.path = message, ""


_Build = Callable[[Any], Any]


def _same(data: Any) -> Any:
    return data


def _as_float(data: Any) -> Any:
    return float(data) if isinstance(data, int) else data


def _at(build: _Build, value: Any, step: str, key: object) -> Any:
    """``build(value)``; a failure's path gains ``step`` formatted with ``key``."""
    try:
        return build(value)
    except _Invalid as exc:
        exc.path = step.format(key) + exc.path
        raise exc from exc.__cause__


@cache
def _builder(tp: Any) -> _Build:
    """The function rebuilding values of type ``tp``, compiled once per type: the type
    hints are read here, not for every value of every stored file."""
    if dataclasses.is_dataclass(tp):
        return _dataclass_builder(tp)
    origin, args = typing.get_origin(tp), typing.get_args(tp)
    if origin in (typing.Union, types.UnionType):
        non_none = [a for a in args if a is not type(None)]
        if len(non_none) != 1:
            return _same
        inner = _builder(non_none[0])
        if type(None) not in args or inner in (_same, _as_float):  # both pass None through
            return inner
        return lambda data: None if data is None else inner(data)
    if origin is tuple:
        return _tuple_builder(args)
    if origin is frozenset:
        item = _builder(args[0])
        return lambda data: frozenset(map(item, data))
    if origin is dict:
        value = _builder(args[1])
        return lambda data: {k: _at(value, v, "[{!r}]", k) for k, v in data.items()}
    return _as_float if tp is float else _same


def _dataclass_builder(tp: Any) -> _Build:
    hints = typing.get_type_hints(tp)
    names = frozenset(f.name for f in dataclasses.fields(tp))
    fields = {name: _builder(hints[name]) for name in names}

    def build(data: Any) -> Any:
        if not isinstance(data, dict):
            raise _Invalid(f"expected an object, got {type(data).__name__}")
        if not names.issuperset(data):
            raise _Invalid(f"unknown field(s) {sorted(set(data) - names)}")
        kwargs = {
            name: value if (make := fields[name]) is _same else _at(make, value, ".{}", name)
            for name, value in data.items()
        }
        try:
            return tp(**kwargs)
        except TypeError as exc:
            raise _Invalid(str(exc)) from exc

    return build


def _tuple_builder(args: tuple[Any, ...]) -> _Build:
    """The builder of ``tuple[X, ...]`` or of the fixed ``tuple[X, Y]``."""
    homogeneous = len(args) == 2 and args[1] is Ellipsis
    items = [_builder(a) for a in args]

    def build(data: Any) -> tuple[Any, ...]:
        if not isinstance(data, list | tuple):
            raise _Invalid(f"expected a list, got {type(data).__name__}")
        if homogeneous:
            if items[0] is _same:
                return tuple(data)
            builders = items[:1] * len(data)
        elif len(data) != len(items):
            side = "shorter" if len(data) < len(items) else "longer"
            raise _Invalid(f"zip() argument 2 is {side} than argument 1")
        else:
            builders = items
        pairs = enumerate(zip(builders, data, strict=True))
        return tuple(v if b is _same else _at(b, v, "[{}]", i) for i, (b, v) in pairs)

    return build


def from_versioned_dict(
    cls: type[T],
    data: Any,
    *,
    version: int,
    what: str,
    remedy: str,
    older: Collection[int] = (),
) -> T:
    """:func:`from_dict` after checking ``data["schema_version"]`` is ``version`` or one of the
    still readable ``older`` ones (every field they lack has a default; the object read is
    upgraded to ``version``); any other is a :class:`ProtocolError` naming ``what`` was read
    and the ``remedy`` (recompute, rebuild, re-run)."""
    found = data.get("schema_version") if isinstance(data, dict) else None
    if found != version and (found not in older or isinstance(found, bool)):
        raise ProtocolError(f"{what} schema_version={found!r} is not {version}; {remedy}")
    return from_dict(cls, {**data, "schema_version": version})


class Schema(NamedTuple):
    """How a :class:`JsonRecord` with a ``schema_version`` is read: the keyword arguments
    of :func:`from_versioned_dict`."""

    version: int
    what: str
    remedy: str
    older: Collection[int] = ()


class JsonRecord:
    """Base of a frozen dataclass stored as JSON: ``to_dict``/``from_dict`` for it.

    A record with a ``schema_version`` field sets ``schema`` to check it when read."""

    __slots__ = ()
    schema: ClassVar[Schema | None] = None

    def to_dict(self) -> dict[str, Any]:
        """The record as plain JSON-able data (:func:`to_dict`)."""
        return to_dict(self)

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Self:
        """The record from :meth:`to_dict` output; :class:`ProtocolError` if it does not fit."""
        if cls.schema is None:
            return from_dict(cls, data)
        return from_versioned_dict(cls, data, **cls.schema._asdict())


def json_safe(data: Any) -> Any:
    """:func:`to_dict` output made strict JSON: a non-finite float (an unbounded memory
    strength, an EFC with no forgetting event) becomes ``"inf"``, ``"-inf"`` or ``"nan"``."""
    if isinstance(data, float) and not math.isfinite(data):
        return "nan" if math.isnan(data) else ("inf" if data > 0 else "-inf")
    if isinstance(data, dict):
        return {k: json_safe(v) for k, v in data.items()}
    if isinstance(data, list):
        return [json_safe(v) for v in data]
    return data
