"""The ``mimic`` family: the scout's exploration, a cognitive map written the way VLMs write it.

A mimic walks like ``scout`` (perfect memory, and homing with its ``b`` knob) but reports a
map as a VLM does, every departure planted and known (docs/user-guide/reference-agents.md):
its own frame ``R(theta) p + t``, free-form labels (:mod:`._phrasing`), position noise,
duplicates on room re-entry, hallucinations, malformed replies (:mod:`._malform`) and
invalid actions. A damaged reply or an invalid action changes nothing in the world, so the
navigation state rolls back and it decides again from the same view; its written map moves on.

The state travels in the reply (``state`` key). Draws about one object (label, noise,
duplicate) are keyed by the episode (a hash of the first request) and the object, draws about
one step by a hash of the step's request; none depends on the knobs, so mimics that differ
only in knobs walk the same path and each knob's effect is measured on paired episodes.
"""

from __future__ import annotations

import copy
import hashlib
import math
from collections.abc import Mapping
from functools import partial
from typing import Any, Final

from pytest_emrd.reference._malform import FAILING, REPAIRABLE, malform, read_state, render
from pytest_emrd.reference._memory import Draw, Entry, uniform
from pytest_emrd.reference._odometry import aim, fresh_odometry, reckon
from pytest_emrd.reference._perceive import fresh_plan, perceive, room_guess
from pytest_emrd.reference._phrasing import (
    HALLUCINATIONS,
    INVALID_ACTIONS,
    NUMBERING,
    label_for,
    pick,
    type_word,
)
from pytest_emrd.reference._read import Briefing, Percept, along
from pytest_emrd.reference._scout import scout_action

#: Half-width (m) of the square the frame's translation is drawn from.
FRAME_SHIFT_M: Final = 10.0
#: Hallucinated objects appear this far ahead (m), within +-45 degrees of the heading.
PHANTOM_RANGE_M: Final = (1.0, 4.0)


def _normal(draw: Draw, name: str) -> tuple[float, float]:
    """Two independent standard normals (Box-Muller) from two uniforms named after ``name``."""
    radius = math.sqrt(-2.0 * math.log(1.0 - draw(f"{name}:r")))
    angle = 2.0 * math.pi * draw(f"{name}:a")
    return radius * math.cos(angle), radius * math.sin(angle)


def fresh_state(key: str, planted: Mapping[str, Any]) -> dict[str, Any]:
    """The state before the first step of the episode keyed ``key`` (hex)."""
    draw = _episode_draw(key)
    frame = [0.0, 0.0, 0.0]
    if planted.get("frame", "own") == "own":
        frame = [round(360.0 * draw("theta"), 4)]
        frame += [round(FRAME_SHIFT_M * (2.0 * draw(axis) - 1.0), 4) for axis in ("tx", "tz")]
    state = {
        "key": key,
        "frame": frame,  # [theta_deg, tx, tz]
        "style": pick(NUMBERING, draw("style")),
        "nav": {"plan": fresh_plan(), "memory": {}, "visit": 0},  # the scout's, room visits
        # written entries by label: id, first visit; frozen ones carry x and z, phantoms a type
        "map": {},
        "seen": {},  # object id -> last step in view
    }
    if planted.get("odometry") == "reckon":
        state["odometry"] = fresh_odometry()
    return state


def _episode_draw(key: str) -> Draw:
    return partial(uniform, bytes.fromhex(key))


def _to_frame(frame: list[float], x: float, z: float) -> tuple[float, float]:
    theta = math.radians(frame[0])
    c, s = math.cos(theta), math.sin(theta)
    return c * x - s * z + frame[1], s * x + c * z + frame[2]


class _Writer:
    """Writes the reported map from the state (one step)."""

    def __init__(self, state: dict[str, Any], planted: Mapping[str, Any]) -> None:
        self.state, self.planted = state, planted
        self.draw = _episode_draw(state["key"])
        self.map: dict[str, Entry] = state["map"]

    def live_label(self, object_id: str) -> str | None:
        # at most one: a duplicate freezes the live label (it gets an ``x``) before a new one
        live = (lb for lb, rec in self.map.items() if rec.get("id") == object_id and "x" not in rec)
        return next(live, None)

    def _new_label(self, object_type: str, name: str) -> str:
        return label_for(
            object_type,
            self.map,
            style=self.state["style"],
            u_phrase=self.draw(f"{name}:phrase"),
            u_qualifier=self.draw(f"{name}:qualifier"),
        )

    def entry_of(self, object_id: str, entry: Mapping[str, Any]) -> dict[str, Any]:
        """How a remembered object is written: its type word, its room (None: none) and its
        position in the frame plus the noise of its last sighting."""
        x, z = _to_frame(self.state["frame"], entry["x"], entry["z"])
        sigma = float(self.planted.get("sigma", 0.0))
        if sigma:
            nx, nz = _normal(self.draw, f"noise:{object_id}:{self.state['seen'][object_id]}")
            x, z = x + sigma * nx, z + sigma * nz
        return {
            "type": type_word(entry["type"]),
            "room": entry.get("room"),
            "x": round(x, 2),
            "z": round(z, 2),
        }

    def label_new(self, memory: Mapping[str, Mapping[str, Any]], visit: int) -> None:
        """Label what is new; note the visit in which an object was first placed in a room."""
        for object_id, entry in memory.items():
            label = self.live_label(object_id)
            if label is None:
                label = self._new_label(entry["type"], object_id)
                self.map[label] = {"id": object_id}
            if entry.get("room") and "visit" not in self.map[label]:
                self.map[label]["visit"] = visit

    def duplicate(self, object_id: str, entry: Mapping[str, Any], room: str, visit: int) -> None:
        """On re-entry into ``room``: maybe write ``object_id`` again under a new label."""
        label = self.live_label(object_id)
        # an entry's room is never "" (:func:`perceive`), so an unknown ``room`` never matches
        if label is None or entry.get("room") != room:
            return
        if self.map[label].get("visit", visit) >= visit:
            return
        if self.draw(f"dup:{object_id}:{visit}") >= float(self.planted.get("dup", 0.0)):
            return
        self.map[label].update(self.entry_of(object_id, entry))  # frozen as written now
        label = self._new_label(entry["type"], f"{object_id}:{visit}")
        self.map[label] = {"id": object_id, "visit": visit}

    def hallucinate(self, percept: Percept, room: str, step: Draw) -> None:
        if step("halluc") >= float(self.planted.get("halluc", 0.0)):
            return
        phrase = pick(HALLUCINATIONS, step("halluc:what"))
        label = label_for(
            phrase, self.map, style=self.state["style"], u_phrase=0.0, u_qualifier=1.0
        )
        low, high = PHANTOM_RANGE_M
        distance = low + (high - low) * step("halluc:distance")
        heading = percept.pose.heading + 90.0 * step("halluc:bearing") - 45.0
        x, z = _to_frame(
            self.state["frame"], *along(percept.pose.x, percept.pose.z, heading, distance)
        )
        self.map[label] = {"type": phrase, "x": round(x, 2), "z": round(z, 2), "room": room}

    def written(self, memory: Mapping[str, Mapping[str, Any]]) -> dict[str, Entry]:
        """The cognitive map as reported: ``{label: {type, room, x, z}}``."""
        out: dict[str, Entry] = {}
        for label, rec in self.map.items():
            if "x" in rec:
                fields = {k: rec[k] for k in ("type", "room", "x", "z")}
            elif rec.get("id") in memory:
                fields = self.entry_of(rec["id"], memory[rec["id"]])
            else:
                continue
            out[label] = {k: v for k, v in fields.items() if v is not None}
        return out


def mimic_reply(
    planted: Mapping[str, Any],
    briefing: Briefing,
    percept: Percept,
    *,
    request: bytes,
    previous: str | None,
) -> str:
    """The reply of a mimic with ``planted`` knobs to the step seeded by ``request``, after its
    ``previous`` reply (None at the first step)."""
    seed = hashlib.sha256(request).digest()
    step = partial(uniform, seed)
    state = read_state(previous) if previous else fresh_state(seed[:8].hex(), planted)
    if "odometry" in state:
        percept = reckon(state["odometry"], percept, state["nav"]["memory"])
    before = copy.deepcopy(state["nav"])
    nav = state["nav"]
    plan = nav["plan"]
    crossing = plan["phase"] == "cross"
    memory, new = perceive(plan, nav["memory"], briefing, percept, planted={}, draw=step)
    nav["memory"] = memory
    if crossing and plan["phase"] == "sweep":
        nav["visit"] += 1
    writer = _Writer(state, planted)
    homing = writer.draw("back") < float(planted.get("back", 0.0))
    action, reasoning = scout_action(plan, briefing, percept, homing=homing)

    room, visit = room_guess(plan), nav["visit"]
    writer.label_new(memory, visit)
    for seen in percept.visible:
        state["seen"][seen.object_id] = percept.step
        writer.duplicate(seen.object_id, memory[seen.object_id], room, visit)
    writer.hallucinate(percept, room, step)

    damaged = step("fail") < float(planted.get("fail", 0.0))
    invalid = not damaged and step("invalid") < float(planted.get("invalid", 0.0))
    in_view = [lb for s in percept.visible if (lb := writer.live_label(s.object_id))]
    if invalid:
        action = pick(INVALID_ACTIONS, step("invalid:which")).format(
            in_view[0] if in_view else "exit"
        )
    if damaged or invalid:  # the world will not move: decide again from the same view
        state["nav"] = before
    if "odometry" in state:
        aim(state["odometry"], action, percept)
    body = {
        "observation": f"I can see: {', '.join(in_view)}." if in_view else "Nothing new in view.",
        "dedup_check": f"{len(new)} new, {len(in_view) - len(new)} already in my map.",
        "cognitive_map": writer.written(memory),
        "action": action,
        "reasoning": reasoning,
    }
    text = render(state, body)
    if damaged:
        return malform(text, pick(FAILING, step("fail:kind")), step("fail:where"))
    if step("repair") < float(planted.get("repair", 0.0)):
        return malform(text, pick(REPAIRABLE, step("repair:kind")), step("repair:wording"))
    return text
