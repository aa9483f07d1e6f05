"""JSON round-trip for the frozen dataclasses that cross stage boundaries.

Field names are the file format: ``to_dict`` writes every field by name, ``from_dict``
rebuilds nested dataclasses and tuples from the type hints and rejects unknown keys so a
typo in a stored file is an error, never silently dropped data.
"""

from __future__ import annotations

import dataclasses
import types
import typing
from collections.abc import Collection
from functools import cache
from typing import Any, TypeVar

from pytest_emrd.errors import ProtocolError

T = TypeVar("T")


def to_dict(obj: Any) -> Any:
    """Plain JSON-able data (dicts, lists, str, numbers, None) from a dataclass tree."""
    if dataclasses.is_dataclass(obj) and not isinstance(obj, type):
        return {f.name: to_dict(getattr(obj, f.name)) for f in dataclasses.fields(obj)}
    if isinstance(obj, tuple | list):
        return [to_dict(v) for v in obj]
    if isinstance(obj, dict):
        return {str(k): to_dict(v) for k, v in obj.items()}
    if isinstance(obj, frozenset | set):
        return sorted(to_dict(v) for v in obj)
    return obj


@cache
def _hints(cls: type) -> dict[str, Any]:
    return typing.get_type_hints(cls)


def from_dict(cls: type[T], data: Any) -> T:
    """Rebuild ``cls`` from :func:`to_dict` output, validating keys on the way."""
    return _build(cls, data, cls.__name__)


def _build(tp: Any, data: Any, where: str) -> Any:
    origin = typing.get_origin(tp)
    if dataclasses.is_dataclass(tp):
        if not isinstance(data, dict):
            raise ProtocolError(f"{where}: expected an object, got {type(data).__name__}")
        names = {f.name for f in dataclasses.fields(tp)}
        unknown = set(data) - names
        if unknown:
            raise ProtocolError(f"{where}: unknown field(s) {sorted(unknown)}")
        hints = _hints(tp)
        kwargs = {
            name: _build(hints[name], value, f"{where}.{name}") for name, value in data.items()
        }
        try:
            return tp(**kwargs)
        except TypeError as exc:
            raise ProtocolError(f"{where}: {exc}") from exc
    if origin in (typing.Union, types.UnionType):
        args = typing.get_args(tp)
        if data is None and type(None) in args:
            return None
        non_none = [a for a in args if a is not type(None)]
        if len(non_none) == 1:
            return _build(non_none[0], data, where)
        return data
    if origin is tuple:
        args = typing.get_args(tp)
        if not isinstance(data, list | tuple):
            raise ProtocolError(f"{where}: expected a list, got {type(data).__name__}")
        if len(args) == 2 and args[1] is Ellipsis:
            return tuple(_build(args[0], v, f"{where}[{i}]") for i, v in enumerate(data))
        return tuple(
            _build(a, v, f"{where}[{i}]") for i, (a, v) in enumerate(zip(args, data, strict=True))
        )
    if origin is frozenset:
        (arg,) = typing.get_args(tp)
        return frozenset(_build(arg, v, where) for v in data)
    if origin is dict:
        _, value_tp = typing.get_args(tp)
        return {k: _build(value_tp, v, f"{where}[{k!r}]") for k, v in data.items()}
    if tp is float and isinstance(data, int):
        return float(data)
    return data


def from_versioned_dict(
    cls: type[T],
    data: Any,
    *,
    version: int,
    what: str,
    remedy: str,
    older: Collection[int] = (),
) -> T:
    """:func:`from_dict` after checking ``data["schema_version"]`` is ``version``.

    ``older`` lists earlier schema versions that are still readable: every field they lack has
    a default in ``cls``, and the object read is upgraded to ``version``. A stored file of any
    other schema is a :class:`ProtocolError` that names ``what`` was read and ``remedy``, what
    to do instead (recompute, rebuild, re-run).
    """
    found = data.get("schema_version") if isinstance(data, dict) else None
    if found != version and (found not in older or isinstance(found, bool)):
        raise ProtocolError(f"{what} schema_version={found!r} is not {version}; {remedy}")
    return from_dict(cls, {**data, "schema_version": version})
