"""The bounded, least-recently-used tables the in-process caches keep."""

from __future__ import annotations

from collections import OrderedDict
from typing import Any


def remember(table: OrderedDict[Any, Any], key: Any, value: Any, capacity: int) -> None:
    """Put ``key: value`` into ``table`` as its newest entry and drop the oldest entries past
    ``capacity`` (the caller holds whatever lock guards ``table``)."""
    table[key] = value
    table.move_to_end(key)
    while len(table) > capacity:
        table.popitem(last=False)
