"""The knobs of the ``mimic`` family: planted map-writing behaviour, settable from the name.

``mimic`` is the registry entry with the shipped defaults; ``mimic-<token>-<token>...``
overrides some of them, each token a letter and a number, or ``spawn``:

=====  ============  =========================================================  ========
token  planted key   meaning                                                    range
=====  ============  =========================================================  ========
s      ``sigma``     position noise: each coordinate of each sighting gets      [0, 5] m
                     independent N(0, sigma^2) noise, metres
p      ``dup``       on re-entering a room, each object mapped there on an      [0, 1]
                     earlier visit and seen again gets a second entry (new
                     label, old entry kept) with probability p
h      ``halluc``    each step, with probability h, one entry for an object     [0, 1]
                     that is not in the office (kept to the end)
q      ``fail``      each reply, with probability q, is damaged beyond repair   [0, 1]
                     (truncated, a missing comma, a ``...`` placeholder): a
                     parse failure
r      ``repair``    each reply that is not damaged, with probability r, has    [0, 1]
                     one repairable slip (code fence, prose, comment, trailing
                     comma)
a      ``invalid``   each reply that is not damaged, with probability a,        [0, 1]
                     names an action the world refuses
b      ``back``      with probability b per episode, once every room is         [0, 1]
                     identified, walks back into the room it will name before
                     ``Term`` (the scout's homing): room re-entries, so
                     duplicates on re-entry and SIR can be measured
spawn  ``frame``     write the map in the spawn frame (default ``own``: a       —
                     seeded rotation + translation per episode)
=====  ============  =========================================================  ========

``mimic-spawn-s0-p0-h0-q0-r0-a0-b0`` is the clean reference: free-form labels only. This
module has no imports from the agents so the registry can use it without import cycles.
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
_NAME = re.compile(rf"^{FAMILY}((?:-(?:spawn|[{''.join(KNOBS)}]\d+(?:\.\d+)?))+)$")


def mimic_knobs(name: str) -> dict[str, Any] | None:
    """Planted overrides a ``mimic-...`` name spells (None: not such a name).

    ``mimic-s0.3-p0.5`` -> ``{"sigma": 0.3, "dup": 0.5}``; ``mimic-spawn`` ->
    ``{"frame": "spawn"}``. A token given twice or a value out of range is a ConfigError.
    """
    match = _NAME.match(name)
    if match is None:
        return None
    planted: dict[str, Any] = {}
    for token in match.group(1).split("-")[1:]:
        key, value = ("frame", "spawn") if token == "spawn" else (KNOBS[token[0]][0], token[1:])
        if key in planted:
            raise ConfigError(f"model={name!r} sets {key} twice; give each knob once.")
        planted[key] = value if key == "frame" else float(value)
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
    if planted.get("frame", "own") not in FRAMES:
        raise ConfigError(
            f"{where}: frame={planted['frame']!r} must be one of {', '.join(FRAMES)}."
        )
