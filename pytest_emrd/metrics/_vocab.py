"""Type vocabulary of the matcher: normalising the type names models write.

Step 2 of :func:`pytest_emrd.metrics.match_map`: an entry's ``object_type`` (then its label)
is normalised by :func:`type_key` and looked up among the episode's ground-truth types, then
in :data:`SYNONYMS`, then without a plural ending.
"""

from __future__ import annotations

import re
from collections.abc import Iterable
from functools import lru_cache
from typing import Final

#: Normalised text -> ground-truth types it may denote, in order of preference.
SYNONYMS: Final[dict[str, tuple[str, ...]]] = {
    "table": ("DiningTable", "CoffeeTable", "SideTable", "Desk"),
    "conferencetable": ("DiningTable",),
    "meetingtable": ("DiningTable",),
    "longtable": ("DiningTable",),
    "receptiondesk": ("Desk",),
    "plant": ("HousePlant",),
    "pottedplant": ("HousePlant",),
    "tv": ("Television",),
    "screen": ("Television",),
    "monitor": ("Television",),
    "fridge": ("Fridge",),
    "refrigerator": ("Fridge",),
    "armchair": ("ArmChair",),
    "sofa": ("Sofa", "ArmChair"),
    "couch": ("Sofa", "ArmChair"),
    "doorway": ("Doorway",),
    "doorframe": ("Doorway",),
    "opening": ("Doorway",),
    "passage": ("Doorway",),
    "exit": ("Door",),
    "exitdoor": ("Door",),
    "frontdoor": ("Door",),
    "counter": ("CounterTop",),
    "kitchencounter": ("CounterTop",),
    "shelf": ("ShelvingUnit", "Shelf"),
    "shelves": ("ShelvingUnit", "Shelf"),
    "bookshelf": ("ShelvingUnit", "Shelf"),
    "coffeemaker": ("CoffeeMachine",),
    "barstool": ("Stool",),
    "computer": ("Laptop",),
    "notebook": ("Laptop",),
}

_ASIDE = re.compile(r"\(.*?\)|\[.*?\]")
_TOKENS = re.compile(r"[a-z0-9]+")
_TRAILING_DIGITS = re.compile(r"\d+$")


@lru_cache(maxsize=4096)
def type_key(text: str) -> str:
    """Normalised comparison key of a type or label: ``"Dining table #2"`` -> ``"diningtable"``.

    Lower-cases, drops ``(...)``/``[...]`` asides, splits on anything that is not a letter or
    digit, drops trailing tokens that are numbers or single letters (instance suffixes), joins
    the rest and strips trailing digits. Empty or suffix-only text gives ``""``.
    """
    tokens = _TOKENS.findall(_ASIDE.sub(" ", text.lower()))
    while len(tokens) > 1 and (tokens[-1].isdigit() or len(tokens[-1]) == 1):
        tokens.pop()
    return _TRAILING_DIGITS.sub("", "".join(tokens))


class TypeResolver:
    """Resolves written type names to the index of a ground-truth type of one episode."""

    def __init__(self, types: Iterable[str]) -> None:
        self.names: list[str] = sorted(set(types))
        """Ground-truth types, sorted; a type's index is its position here."""
        self.index: dict[str, int] = {t: i for i, t in enumerate(self.names)}
        self._key_to_type = {type_key(t): i for t, i in self.index.items()}
        for key, candidates in SYNONYMS.items():
            if key not in self._key_to_type:
                hit = next((self.index[c] for c in candidates if c in self.index), None)
                if hit is not None:
                    self._key_to_type[key] = hit
        self.known: dict[tuple[str, str], int] = {}
        """``(object_type, label)`` -> type index, for every entry resolved so far."""

    def resolve(self, object_type: str, label: str) -> int:
        """Type index of an entry (its ``object_type`` first, then its label); -1 if none."""
        hit = self.known.get((object_type, label))
        if hit is None:
            hit = self._resolve_text(object_type)
            if hit < 0:
                hit = self._resolve_text(label)
            self.known[(object_type, label)] = hit
        return hit

    def _resolve_text(self, text: str) -> int:
        key = type_key(text)
        plurals = (key[:-1] if key.endswith("s") else "", key[:-2] if key.endswith("es") else "")
        for candidate in (key, *plurals):
            if candidate and candidate in self._key_to_type:
                return self._key_to_type[candidate]
        return -1
