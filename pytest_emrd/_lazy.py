"""Made on demand: lazy re-exports for a package ``__init__`` (PEP 562), and the bounded,
least-recently-used tables the in-process caches keep.

A package names its public API and the private module defining each name, imported on first
use: a light submodule (the model registry) then no longer imports its heavy siblings (httpx,
the reference agents) into every pytest process at start-up.
"""

from __future__ import annotations

import importlib
import sys
from collections import OrderedDict
from collections.abc import Callable, Mapping, Sequence
from typing import Any


def lazy_exports(
    package: str, modules: Mapping[str, Sequence[str]]
) -> tuple[Callable[[str], Any], Callable[[], list[str]], list[str]]:
    """``__getattr__``, ``__dir__`` and ``__all__`` for ``package``, whose public names are
    defined in its submodules (``{"_clients": ("make_client", ...), ...}``)."""
    owner = {name: module for module, names in modules.items() for name in names}

    def __getattr__(name: str) -> Any:
        if name not in owner:
            raise AttributeError(f"module {package!r} has no attribute {name!r}")
        value = getattr(importlib.import_module(f"{package}.{owner[name]}"), name)
        setattr(sys.modules[package], name, value)  # later look-ups skip this function
        return value

    def __dir__() -> list[str]:
        return sorted(set(vars(sys.modules[package])) | owner.keys())

    return __getattr__, __dir__, sorted(owner)


def remember(table: OrderedDict[Any, Any], key: Any, value: Any, capacity: int) -> None:
    """Put ``key: value`` into ``table`` as its newest entry and drop the oldest entries past
    ``capacity`` (the caller holds whatever lock guards ``table``)."""
    table[key] = value
    table.move_to_end(key)
    while len(table) > capacity:
        table.popitem(last=False)
