"""Planted memory of the scripted agents: what their reported cognitive map keeps.

The map is an ordered ``label -> entry`` dict in *memory order*: objects in view this
step move to the end (nearest last), new objects are appended. After the view is merged,
one policy decides what survives; objects in view always survive except under a window
smaller than the view.

* ``perfect`` — nothing is forgotten.
* ``decay`` (``mean_steps`` = m) — each out-of-view object is dropped at each step with
  hazard :math:`h = 1 - e^{-1/m}`, so the time an object survives out of view is
  geometric with :math:`S(t) = e^{-t/m}` (exponential retention, mean about m steps).
* ``window`` (``k``) — at most k objects, the least recently seen dropped first.
* ``serial`` (``mean_steps`` = m) — U-shaped retention: of the n objects discovered so
  far, the first and last thirds (by discovery rank) are protected; middle-third
  objects out of view decay with hazard :math:`1 - e^{-1/m}`.

Randomness comes from :func:`uniform`, a hash of the request content and the label, so
the same request always forgets the same objects.
"""

from __future__ import annotations

import hashlib
import math
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Final

from pytest_emrd.errors import ConfigError

Entry = dict[str, Any]
MEMORIES: Final[tuple[str, ...]] = ("perfect", "decay", "window", "serial")


def uniform(seed: bytes, label: str) -> float:
    """A number in [0, 1) fixed by ``seed`` (request content) and ``label``."""
    digest = hashlib.sha256(seed + b"\x1f" + label.encode()).digest()
    return int.from_bytes(digest[:8], "big") / 2**64


def merge_view(memory: Mapping[str, Entry], view: Sequence[tuple[str, Entry]]) -> dict[str, Entry]:
    """Memory with ``view`` (label, entry; farthest first) refreshed to the end."""
    seen = {label for label, _ in view}
    merged = {label: entry for label, entry in memory.items() if label not in seen}
    merged.update(view)
    return merged


def _hazard(mean_steps: float) -> float:
    return 1.0 - math.exp(-1.0 / mean_steps)


def apply_memory(
    memory: dict[str, Entry],
    *,
    in_view: frozenset[str],
    planted: Mapping[str, Any],
    discovery: Sequence[str],
    draw: Callable[[str], float],
) -> dict[str, Entry]:
    """The entries the planted memory keeps this step (``memory`` already merged).

    ``discovery`` lists every label ever discovered, in order of first discovery;
    ``draw(label)`` is this step's uniform number for ``label``.
    """
    kind = planted.get("memory", "perfect")
    if kind == "perfect":
        return memory
    if kind == "window":
        k = int(planted["k"])
        return dict(list(memory.items())[-k:])
    if kind not in ("decay", "serial"):
        raise ConfigError(f"planted memory={kind!r} is not one of {', '.join(MEMORIES)}.")
    hazard = _hazard(float(planted["mean_steps"]))
    exposed = set(memory) - in_view
    if kind == "serial":
        n = len(discovery)
        middle = {label for rank, label in enumerate(discovery) if n / 3 <= rank < 2 * n / 3}
        exposed &= middle
    return {
        label: e for label, e in memory.items() if label not in exposed or draw(label) >= hazard
    }
