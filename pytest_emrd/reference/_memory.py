"""Planted memory of the scripted agents: what their reported cognitive map keeps.

The map is an ordered ``label -> entry`` dict in *memory order*: objects in view this step
move to the end (nearest last), new objects are appended. Then one policy decides what
survives; objects in view always survive except under a window smaller than the view.

* ``perfect`` — nothing is forgotten; ``none`` — the reported map is always empty (``prior``).
* ``decay`` (``mean_steps`` = m >= 1) — at every step an out-of-view object is dropped with
  probability :math:`p = 1/m`, independently. The out-of-view steps up to and including the
  drop are geometric on {1, 2, ...}: :math:`P(T = t) = (1 - p)^{t-1} p`,
  :math:`S(t) = (1 - 1/m)^t`, mean exactly m, so with right-censoring ``sum t_j / d``
  (Eq. SMLE) is its maximum-likelihood estimate and the Ebbinghaus EFC recovers m without a
  discretisation bias (a hazard ``1 - exp(-1/m)`` would give a mean of about m + 0.5).
* ``window`` (``k``) — at most k objects, the least recently seen dropped first.
* ``serial`` (``mean_steps`` = m) — U-shaped retention: objects whose discovery rank falls in
  the first or last third of the *expected* total (the prompt inventory's object count, else
  the number discovered so far) are protected; middle-third objects decay as under ``decay``.

Randomness comes from :func:`uniform`, a hash of the request content and the label, so the
same request always forgets the same objects.
"""

from __future__ import annotations

import hashlib
from collections.abc import Callable, Mapping, Sequence
from typing import Any, Final

from pytest_emrd.errors import ConfigError

Entry = dict[str, Any]
#: A uniform number in [0, 1) per name, fixed by the request (:func:`uniform`).
Draw = Callable[[str], float]
MEMORIES: Final[tuple[str, ...]] = ("perfect", "none", "decay", "window", "serial")


def uniform(seed: bytes, label: str) -> float:
    """A number in [0, 1) fixed by ``seed`` (request content) and ``label``."""
    digest = hashlib.sha256(seed + b"\x1f" + label.encode()).digest()
    return int.from_bytes(digest[:8], "big") / 2**64


def merge_view(memory: Mapping[str, Entry], view: dict[str, Entry]) -> dict[str, Entry]:
    """Memory with ``view`` (label -> entry; farthest first) refreshed to the end."""
    return {label: entry for label, entry in memory.items() if label not in view} | view


def drop_probability(mean_steps: float) -> float:
    """Per-step probability ``1/m`` that an out-of-view object is dropped (mean ``m`` steps)."""
    if not mean_steps >= 1.0:
        raise ConfigError(
            f"planted mean_steps={mean_steps!r} must be >= 1: a retention counted in whole "
            "steps cannot average less than one step."
        )
    return 1.0 / mean_steps


def apply_memory(
    memory: dict[str, Entry],
    *,
    in_view: frozenset[str],
    planted: Mapping[str, Any],
    discovery: Sequence[str],
    draw: Draw,
    expected: int | None = None,
) -> dict[str, Entry]:
    """The entries the planted memory keeps this step (``memory`` already merged):
    ``discovery`` lists labels in order of first discovery, ``draw(label)`` is this step's
    uniform number, ``expected`` the inventory's object total (None or 0: unknown)."""
    kind = planted.get("memory", "perfect")
    if kind == "perfect":
        return memory
    if kind == "none":
        return {}
    if kind == "window":
        return dict(list(memory.items())[-int(planted["k"]) :])
    if kind not in ("decay", "serial"):
        raise ConfigError(f"planted memory={kind!r} is not one of {', '.join(MEMORIES)}.")
    p = drop_probability(float(planted["mean_steps"]))
    exposed = set(memory) - in_view
    if kind == "serial":
        n = expected or len(discovery)
        exposed &= {label for rank, label in enumerate(discovery) if n / 3 <= rank < 2 * n / 3}
    return {label: e for label, e in memory.items() if label not in exposed or draw(label) >= p}
