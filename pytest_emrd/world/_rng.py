"""A seeded random source whose stream is stable across Python and numpy versions.

Layouts must be identical bit for bit wherever they are generated (cassettes key frames by
their pixels). numpy's ``Generator`` methods and :mod:`random`'s helpers may change their
algorithms between releases; only ``random.Random.random()`` is guaranteed to repeat its
sequence, so every draw here is derived from that one method.
"""

from __future__ import annotations

import random
from collections.abc import Sequence
from typing import TypeVar

T = TypeVar("T")


class StableRng:
    """Uniform draws built on ``random.Random(seed).random()`` only."""

    def __init__(self, seed: int | str) -> None:
        self._random = random.Random(seed).random

    def random(self) -> float:
        """A float in ``[0, 1)``."""
        return self._random()

    def uniform(self, low: float, high: float) -> float:
        """A float in ``[low, high)``."""
        return low + (high - low) * self._random()

    def integer(self, low: int, high: int) -> int:
        """An int in ``[low, high]`` (both ends included)."""
        return low + min(int(self._random() * (high - low + 1)), high - low)

    def choice(self, items: Sequence[T]) -> T:
        """One element of a non-empty sequence."""
        return items[self.integer(0, len(items) - 1)]

    def shuffled(self, items: Sequence[T]) -> list[T]:
        """A new list with the items in random order (Fisher-Yates)."""
        out = list(items)
        for i in range(len(out) - 1, 0, -1):
            j = self.integer(0, i)
            out[i], out[j] = out[j], out[i]
        return out
