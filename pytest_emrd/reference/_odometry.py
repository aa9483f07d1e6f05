"""Dead reckoning: the pose an agent keeps when it ignores the engine's ``Pose:`` line.

The ``reckon`` knob of the mimic (``mimic-reckon``) measures what our reading of "perfect
odometry" is worth (docs/interpretation/world.md, "The pose in every message"). Such a mimic
starts at the spawn origin, as the prompt says, and integrates only what it asked for and the
feedback confirmed ("... succeeded"), as a model without the line would have to:

* a turn adds its angle;
* a ``Goto`` of an object ends :data:`STAND_OFF_M` short of where the agent placed the
  object, facing it along the nearest quarter turn (``Goto`` ends facing a side of the object);
* a ``Goto`` of a doorway ends :data:`THROUGH_M` past where it placed the doorway, facing on.

``Goto`` does not say which side of an object it ended at, so after one the agent picks, of
the four quarter-turn headings, the one under which the objects it placed before and sees
again agree best on where it stands (their median), as a model would read its own map
against the frame; with nothing placed in view it keeps the expected arrival. What it
misplaced stays misplaced: every later placement inherits the drift.
"""

from __future__ import annotations

import dataclasses
import math
import re
from collections.abc import Mapping
from typing import Any, Final

import numpy as np

from pytest_emrd.reference._read import Percept, along, placed
from pytest_emrd.trajectory import Pose

#: Where a confirmed ``Goto`` of an object is taken to end, short of the object's placement:
#: the engine's 0.7 m stand-off from the footprint plus about half a piece of furniture.
STAND_OFF_M: Final = 1.0
#: Past a doorway's placement, where a confirmed ``Goto`` through it ends (the engine's 1 m).
THROUGH_M: Final = 1.0
TURNS: Final = {"Left": -90.0, "Right": 90.0, "Around": 180.0}
_ACTION = re.compile(r"^(?P<verb>Goto|Turn)\((?P<arg>[^)]*)\)$")


def fresh_odometry() -> dict[str, Any]:
    """The dead-reckoning state at the first step: the spawn origin, nothing asked yet."""
    return {"pose": [0.0, 0.0, 0.0], "asked": "", "goal": None}


def reckon(
    odometry: dict[str, Any], percept: Percept, placed: Mapping[str, Mapping[str, Any]]
) -> Percept:
    """``percept`` with its pose replaced by the reckoned one, after applying the last action
    if the feedback confirmed it (a ``Goto`` re-sighted against the objects ``placed`` in the
    agent's own memory, id -> ``x``, ``z``); ``odometry`` is updated in place."""
    x, z, heading = odometry["pose"]
    asked = _ACTION.match(odometry["asked"]) if percept.confirmed else None
    if asked and asked["verb"] == "Turn":
        heading = (heading + TURNS.get(asked["arg"], 0.0)) % 360.0
    elif asked and odometry["goal"] is not None:
        gx, gz, doorway = odometry["goal"]
        heading = round(math.degrees(math.atan2(gx - x, gz - z)) / 90.0) * 90.0 % 360.0
        ahead = THROUGH_M if doorway else -STAND_OFF_M
        x, z = along(gx, gz, heading, ahead)
        x, z, heading = _resight(percept, placed, (x, z, heading))
    odometry["pose"] = [round(x, 4), round(z, 4), heading]
    return dataclasses.replace(percept, pose=Pose(*odometry["pose"]))


def _resight(
    percept: Percept, placed: Mapping[str, Mapping[str, Any]], expected: tuple[float, float, float]
) -> tuple[float, float, float]:
    """The heading (and the position it implies) under which the re-sighted objects agree best;
    ``expected`` when none is re-sighted."""
    again = [s for s in percept.visible if s.object_id in placed]
    if not again:
        return expected
    known = np.array([[placed[s.object_id]["x"], placed[s.object_id]["z"]] for s in again])
    bearing = np.radians([s.bearing for s in again])
    distance = np.array([s.distance for s in again])
    candidates = []
    for heading in dict.fromkeys((expected[2], 0.0, 90.0, 180.0, 270.0)):  # expected first, once
        angle = np.radians(heading) + bearing
        stands = known - distance[:, None] * np.stack([np.sin(angle), np.cos(angle)], axis=1)
        x, z = np.median(stands, axis=0)
        spread = round(float(np.median(np.hypot(stands[:, 0] - x, stands[:, 1] - z))), 6)
        candidates.append((spread, float(x), float(z), heading))
    _, x, z, heading = min(candidates, key=lambda c: c[0])  # ties: the expected heading
    return x, z, heading


def aim(odometry: dict[str, Any], action: str, percept: Percept) -> None:
    """Note the action sent at this step and, for a ``Goto``, where the agent placed its target
    (the instance named, else the nearest of the type named; None when nothing in view)."""
    odometry.update(asked=action, goal=None)
    asked = _ACTION.match(action)
    if asked is None or asked["verb"] != "Goto":
        return
    name = asked["arg"].strip().lower()
    named = [s for s in percept.visible if s.object_id.lower() == name]
    typed = [s for s in percept.visible if s.object_type.lower() == name]
    target = min(named or typed, key=lambda s: s.distance, default=None)
    if target is not None:
        odometry["goal"] = [*placed(percept, target), target.object_type == "Doorway"]
