"""The environmental conditions: what ``baseline``, ``low_light`` and ``texture`` change.

The one table both backends read. A surface at distance ``d`` is mixed with the fog colour
in proportion ``min(1, fog * (d / reach)^4)``, its reach the visibility distance (landmarks:
the drawn distance); a pixel is legible while that proportion is at most ``fog``.
Why these numbers and what low light costs: ``docs/interpretation/world.md`` ("Visibility").
"""

from __future__ import annotations

from collections.abc import Mapping
from dataclasses import dataclass
from typing import Final

from pytest_emrd.errors import check_choice
from pytest_emrd.trajectory import CONDITIONS


@dataclass(frozen=True)
class ConditionParams:
    """What one condition does to the world."""

    name: str
    visibility_distance: float
    """Metres: the fog's scale; beyond it, within a few tenths of a metre, fog hides what
    is not a landmark (THOR: ``visibilityDistance`` of such objects)."""
    draw_distance: float
    """Metres: the fog's scale for landmarks (doorways, the exit); objects farther than
    this are not drawn."""
    light_factor: float
    """Multiplier on all surface brightness (1.0 = baseline)."""
    fog: float
    """Fraction of fog colour mixed into a surface at its reach: the most fog a pixel holds
    and still shows its surface legibly."""
    fog_color: tuple[int, int, int]
    randomize_palette: bool
    """Whether wall, floor and object colours are drawn at random per episode seed."""


_TABLE: Final[Mapping[str, ConditionParams]] = {
    "baseline": ConditionParams("baseline", 3.1, 7.0, 1.0, 0.85, (214, 216, 220), False),
    "low_light": ConditionParams("low_light", 2.9, 7.0, 0.5, 0.5, (56, 56, 60), False),
    "texture": ConditionParams("texture", 3.1, 7.0, 1.0, 0.85, (214, 216, 220), True),
}


def condition_params(name: str) -> ConditionParams:
    """The parameters of condition ``name``; ConfigError for an unknown name.

    :param name: ``baseline``, ``low_light`` or ``texture``.
    :returns: The condition's :class:`ConditionParams`.
    """
    check_choice("condition", name, CONDITIONS, hint="Pick one of the paper's conditions.")
    return _TABLE[name]
