"""The one table between THOR ``objectId`` values and EMRD ``Type_N`` ids.

:func:`~pytest_emrd.world.thor.build_house` names every house object and door in THOR's
style (``Desk|1|0``, ``door|1|2``) and writes ``thor id -> EMRD id`` into
``house["metadata"]["emrd"]["ids"]``; everything else reads that table through
:class:`IdTable`. THOR objects the layout never placed (walls, floors, children spawned
by the build) have no EMRD id and are ignored.
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass, field
from typing import Any

from pytest_emrd.errors import ConfigError


@dataclass(frozen=True)
class IdTable:
    """Bidirectional map THOR objectId <-> EMRD object id."""

    to_emrd: Mapping[str, str]
    """THOR objectId -> EMRD id."""
    to_thor: Mapping[str, str] = field(init=False, repr=False)
    """EMRD id -> THOR objectId."""

    def __post_init__(self) -> None:
        inverse = {ours: thor for thor, ours in self.to_emrd.items()}
        if len(inverse) != len(self.to_emrd):
            raise ConfigError("the THOR id table maps two THOR objects to one EMRD id.")
        object.__setattr__(self, "to_thor", inverse)

    @classmethod
    def from_house(cls, house: Mapping[str, Any]) -> IdTable:
        try:
            table = house["metadata"]["emrd"]["ids"]
        except (KeyError, TypeError):
            raise ConfigError(
                "house has no metadata.emrd.ids table; build it with "
                "pytest_emrd.world.thor.build_house."
            ) from None
        return cls(dict(table))

    def emrd(self, thor_id: str) -> str | None:
        """The EMRD id of a THOR object, or None if the layout never placed it."""
        return self.to_emrd.get(thor_id)

    def thor(self, emrd_id: str) -> str:
        """The THOR objectId of an EMRD object (KeyError if unknown)."""
        return self.to_thor[emrd_id]
