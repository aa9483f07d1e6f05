"""Reading an action text: ``Goto(target)``, ``Turn(Left|Right|Around)``, ``Term(room)``.

Names are case-insensitive and surrounding whitespace or a trailing full stop is
tolerated; anything else is an :class:`Invalid` action, which the simulator turns into a
failed step (never an exception). Stand-in until :mod:`pytest_emrd.world` exports the
shared parser: both backends must read actions identically.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

_ACTION = re.compile(r"^\s*(?P<verb>[A-Za-z]+)\s*\(\s*(?P<arg>[^()]*?)\s*\)\s*\.?\s*$")
TURNS = {"left": "Left", "right": "Right", "around": "Around"}
USAGE = "use Goto(target), Turn(Left|Right|Around) or Term(room)"


@dataclass(frozen=True)
class Goto:
    target: str


@dataclass(frozen=True)
class Turn:
    direction: str
    """``Left``, ``Right`` or ``Around``."""


@dataclass(frozen=True)
class Term:
    room: str


@dataclass(frozen=True)
class Invalid:
    reason: str


Action = Goto | Turn | Term | Invalid


def parse(text: str) -> Action:
    """The action ``text`` names, or :class:`Invalid` saying why it cannot be executed."""
    match = _ACTION.match(text or "")
    if match is None:
        return Invalid(
            f"cannot read {text!r}; use Goto(target), Turn(Left|Right|Around) or Term(room)"
        )
    verb, arg = match["verb"].lower(), match["arg"]
    if verb == "goto" and arg:
        return Goto(arg)
    if verb == "turn" and arg.lower() in TURNS:
        return Turn(TURNS[arg.lower()])
    if verb == "term" and arg:
        return Term(arg)
    return Invalid(f"{text.strip()!r} is not an action; {USAGE}")
