"""The action grammar, and what the agent is told after an action: one wording shared by
every backend.

:func:`parse_action` reads ``Goto(target)``, ``Turn(Left|Right|Around)`` and ``Term(room)``,
case-insensitive and whitespace tolerant, quotes around the argument and a trailing full
stop accepted (``goto( "Desk_2" ).``).
:func:`execute` runs an action text with one handler per verb: a step after the episode
ended, unreadable text, or a handler raising :class:`ActionFailed` yields ``"<Action>
failed: <reason>."``, else ``"<Action> succeeded<note>."``; :func:`with_pose` appends the
odometry line in the spawn frame. The failure reasons and the Goto target choice live here
too, so the backends cannot drift apart; recorded cassettes hold this text (any change
bumps ``WORLD_VERSION``). Under ``vision`` (``symbolic=False``) no message names an object
id: ``Goto`` takes a type (an instance suffix such as ``Desk_2`` is ignored) and goes to the
nearest visible object of that type.
"""

from __future__ import annotations

import re
from collections.abc import Callable, Mapping, Sequence
from dataclasses import dataclass

from pytest_emrd.errors import check_choice
from pytest_emrd.rooms import ROOM_NAMES, SLUG_ROOMS
from pytest_emrd.trajectory import Pose
from pytest_emrd.world._geometry import heading_in_spawn_frame, spawn_frame_point
from pytest_emrd.world._model import Observation, View, VisibleObject, WorldPose

_ACTION = re.compile(r"^\s*(goto|turn|term)\s*\(\s*(.*?)\s*\)\s*\.?\s*$", re.IGNORECASE | re.DOTALL)
_QUOTES = "\"'`"
TURNS = {"left": -90.0, "right": 90.0, "around": 180.0}
GRAMMAR = "Goto(target), Turn(Left|Right|Around) or Term(room)"


@dataclass(frozen=True)
class Action:
    verb: str
    """``Goto``, ``Turn`` or ``Term``."""
    arg: str
    """The argument as written, quotes and surrounding blanks removed."""

    def __str__(self) -> str:
        return f"{self.verb}({self.arg})"


def parse_action(text: str) -> Action | None:
    """The action in ``text``, or None when it does not follow the grammar."""
    match = _ACTION.match(text)
    if match is None:
        return None
    verb = match.group(1).capitalize()
    arg = match.group(2).strip().strip(_QUOTES).strip()
    return Action(verb, arg)


def normalise(name: str) -> str:
    """Matching key for ids, types and room names: case, blanks and underscores ignored."""
    return re.sub(r"[\s_]+", "", name).lower()


Handler = Callable[[Action], str]
"""Executes one parsed action; returns the success note or raises :class:`ActionFailed`."""
TERM_NOTE = ": the episode is over"
OTHER_NOTE = ": the episode is over; {arg!r} is not one of the four rooms (recorded as Other)"
_INSTANCE = re.compile(r"\d+$")


class ActionFailed(Exception):
    """An action that could not be executed; the message is the reason shown to the agent."""


def execute(text: str, handlers: Mapping[str, Handler], *, over: bool) -> tuple[bool, str]:
    """``(success, message)`` of executing action ``text`` (every action fails when ``over``:
    the episode has ended); never raises for a bad action."""
    parsed = parse_action(text)
    shown = str(parsed) if parsed else "Action"
    try:
        if over:
            raise ActionFailed("the episode is over")
        if parsed is None:
            snippet = " ".join(text.split())[:80]
            raise ActionFailed(f"could not read {snippet!r}; use {GRAMMAR}")
        note = handlers[parsed.verb](parsed)
    except ActionFailed as failure:
        return False, f"{shown} failed: {failure}."
    return True, f"{shown} succeeded{note}."


class SemanticStep:
    """The ``step``, ``Goto`` and ``Term`` of both backends: an action text -> :meth:`_goto`,
    the backend's ``_turn`` or :meth:`_term` (via :func:`execute`) -> :meth:`_observe`. The
    backend provides ``_in_view()`` (the objects in view),
    ``_reach(object_id)`` (moves for ``Goto``; False: no spot to stand), ``_view()`` (world
    pose, objects in view, frame digest and view), ``_require()`` and the attributes below."""

    _steps: int = 0
    _ended: bool = False
    _terminal: str | None = None
    _symbolic: bool = True
    _spawn: WorldPose
    _rooms: Mapping[str, str]
    _turn: Handler
    _in_view: Callable[[], tuple[VisibleObject, ...]]
    _reach: Callable[[str], bool]
    _view: Callable[[], tuple[WorldPose, tuple[VisibleObject, ...], str, View]]
    _require: Callable[[], object]

    def step(self, action: str) -> Observation:
        """Execute one action text; never raises for a bad action (the step is consumed)."""
        self._require()
        self._steps += 1
        handlers = {"Goto": self._goto, "Turn": self._turn, "Term": self._term}
        return self._observe(*execute(action, handlers, over=self._ended))

    def _goto(self, action: Action) -> str:
        """Without symbolic ids the target is a type (an instance number is dropped) and no
        message names an id; with them the success note names the instance a type chose."""
        symbolic = self._symbolic
        if not action.arg:
            example = "an object id such as Desk_2 or a type" if symbolic else "an object type"
            raise ActionFailed(f"Goto needs a target: {example}, e.g. Goto(Desk)")
        key = normalise(action.arg)
        key = key if symbolic else _INSTANCE.sub("", key)
        seen = self._in_view()
        chosen = choose_target(key, seen, symbolic=symbolic)
        if chosen is None:
            if not symbolic:
                raise ActionFailed(f"no object of type {action.arg!r} is visible")
            shown = ", ".join(sorted(v.object_id for v in seen)) or "nothing"
            raise ActionFailed(f"no visible object matches {action.arg!r}. Visible: {shown}")
        target = chosen.object_id
        if not self._reach(target):
            where = target if symbolic else f"the nearest {chosen.object_type}"
            raise ActionFailed(f"there is no free spot to stand at {where}")
        return "" if not symbolic or normalise(target) == key else f": moved to {target}"

    def visible_ids(self) -> tuple[str, ...]:
        """Ids of the objects in view, sorted."""
        self._require()
        return tuple(v.object_id for v in self._in_view())

    @property
    def spawn_pose(self) -> WorldPose:
        """Where the episode started, world frame."""
        self._require()
        return self._spawn

    def _begin(self, symbolic: bool) -> Observation:
        """The first observation of a new episode: no step taken, no Term yet."""
        self._steps, self._ended, self._terminal, self._symbolic = 0, False, None, symbolic
        return self._observe(True, "Episode started.")

    def _observe(self, success: bool, message: str) -> Observation:
        world, visible, digest, view = self._view()
        pose = observed_pose(self._spawn, world)
        return Observation(
            step=self._steps,
            pose=pose,
            success=success,
            feedback=with_pose(message, pose),
            visible=visible,
            frame_digest=digest,
            view=view,
            done=self._ended,
            terminal_room=self._terminal,
        )

    def _term(self, action: Action) -> str:
        self._ended = True
        self._terminal, note = term(self._rooms, action)
        return note


def turn_degrees(action: Action) -> float:
    """Clockwise degrees of ``Turn(Left|Right|Around)``: -90, 90 or 180."""
    delta = TURNS.get(normalise(action.arg))
    if delta is None:
        raise ActionFailed(
            f"cannot turn {action.arg!r}; use Turn(Left), Turn(Right) or Turn(Around)"
        )
    return delta


def spawn_room_name(spawn_room: str) -> str:
    """The canonical name of ``spawn_room``, given as a name or a slug (ConfigError else)."""
    name = SLUG_ROOMS.get(spawn_room, spawn_room)
    check_choice("spawn_room", name, [*ROOM_NAMES, *SLUG_ROOMS])
    return name


def room_table(aliases: Mapping[str, str] | None = None) -> dict[str, str]:
    """Matching key -> canonical room for ``Term``: the four rooms plus ``aliases``."""
    rooms = {normalise(r): r for r in ROOM_NAMES}
    for alias, room in (aliases or {}).items():
        check_choice(f"room_aliases[{alias!r}]", room, ROOM_NAMES)
        rooms[normalise(alias)] = room
    return rooms


def term(rooms: Mapping[str, str], action: Action) -> tuple[str | None, str]:
    """``(room, note)`` of ``Term(r)``: the canonical room ``r`` names (``rooms`` from
    :func:`room_table`), or None when it is not one of the four rooms (column X, Other)."""
    room = rooms.get(normalise(action.arg))
    return room, TERM_NOTE if room else OTHER_NOTE.format(arg=action.arg)


def choose_target(
    key: str, seen: Sequence[VisibleObject], *, symbolic: bool
) -> VisibleObject | None:
    """The object in view ``Goto`` of ``key`` means, or None: with ``symbolic`` ids an
    instance id wins, else the nearest object of that type (ties by id)."""
    for v in seen if symbolic else ():
        if normalise(v.object_id) == key:
            return v
    typed = [v for v in seen if normalise(v.object_type) == key]
    return min(typed, key=lambda v: (v.distance, v.object_id), default=None)


def observed_pose(spawn: WorldPose, pose: WorldPose) -> Pose:
    """The agent's odometry: ``pose`` in the spawn frame, to 0.1 mm, never ``-0.0``."""
    x, z = spawn_frame_point(spawn, pose.x, pose.z)
    return Pose(x, z, heading_in_spawn_frame(spawn, pose.heading))


def with_pose(message: str, pose: Pose) -> str:
    """Engine feedback: ``message`` followed by the odometry line."""
    return f"{message} Pose: x={_fmt(pose.x)} z={_fmt(pose.z)} heading={pose.heading:.0f}."


def _fmt(value: float) -> str:
    """Centimetre text of a coordinate, never ``-0.00``."""
    return f"{round(value, 2) + 0.0:.2f}"
