"""The knobs of the ``mimic`` family: planted map-writing behaviour, settable from the name.

``mimic`` is the registry entry with the shipped defaults; ``mimic-<token>-<token>...``
overrides some of them, each token a letter of :data:`KNOBS` and a number (``s0.3``), or
``spawn`` (``frame: spawn``, the map in the spawn frame instead of a seeded frame of its own)
or ``reckon`` (``odometry: reckon``, the pose dead-reckoned instead of read off the feedback).
What each knob plants and its default: the table in docs/user-guide/reference-agents.md.
``mimic-spawn-s0-p0-h0-q0-r0-a0-b0`` is the clean reference: free-form labels only. The
registry checks them here; the agents themselves (:mod:`pytest_emrd.reference`) plant them.
"""

from __future__ import annotations

import re
from collections.abc import Mapping
from typing import Any, Final

from pytest_emrd.errors import ConfigError, check_range

FAMILY: Final = "mimic"
#: Name token letter -> (planted key, upper bound).
KNOBS: Final[dict[str, tuple[str, float]]] = {
    "s": ("sigma", 5.0),
    "p": ("dup", 1.0),
    "h": ("halluc", 1.0),
    "q": ("fail", 1.0),
    "r": ("repair", 1.0),
    "a": ("invalid", 1.0),
    "b": ("back", 1.0),
}
FRAMES: Final[tuple[str, ...]] = ("own", "spawn")
ODOMETRY: Final[tuple[str, ...]] = ("engine", "reckon")
#: Name tokens without a number -> (planted key, value).
WORDS: Final[dict[str, tuple[str, str]]] = {
    "spawn": ("frame", "spawn"),
    "reckon": ("odometry", "reckon"),
}
_NAME = re.compile(rf"^{FAMILY}((?:-(?:{'|'.join(WORDS)}|[{''.join(KNOBS)}]\d+(?:\.\d+)?))+)$")


def mimic_knobs(name: str) -> dict[str, Any] | None:
    """Planted overrides a ``mimic-...`` name spells (``mimic-s0.3-p0.5`` -> ``{"sigma": 0.3,
    "dup": 0.5}``), None for another name; a knob given twice or out of range: ConfigError."""
    match = _NAME.match(name)
    if match is None:
        return None
    planted: dict[str, Any] = {}
    for token in match.group(1).split("-")[1:]:
        key, value = WORDS.get(token) or (KNOBS[token[0]][0], float(token[1:]))
        if key in planted:
            raise ConfigError(f"model={name!r} sets {key} twice; give each knob once.")
        planted[key] = value
    check_knobs(f"model={name!r}", planted)
    return planted


def check_knobs(where: str, planted: Mapping[str, Any]) -> None:
    """ConfigError naming ``where`` when a planted mimic knob is out of range."""
    for key, top in KNOBS.values():
        if key in planted:
            value = planted[key]
            if isinstance(value, bool) or not isinstance(value, int | float):
                raise ConfigError(f"{where}: {key}={value!r} must be a number.")
            check_range(f"{where}: {key}", value, 0.0, top)
    for key, allowed, default in (("frame", FRAMES, "own"), ("odometry", ODOMETRY, "engine")):
        if planted.get(key, default) not in allowed:
            raise ConfigError(
                f"{where}: {key}={planted[key]!r} must be one of {', '.join(allowed)}."
            )
