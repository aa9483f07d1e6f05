"""The action grammar the world reads: ``Goto(target)``, ``Turn(Left|Right|Around)``,
``Term(room)``.

Case-insensitive and whitespace tolerant; quotes around the argument and a trailing full
stop are accepted (``goto( "Desk_2" ).``). Anything else is not an action: the caller
consumes the step and reports why.
"""

from __future__ import annotations

import re
from dataclasses import dataclass

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
