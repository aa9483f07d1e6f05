"""The environmental conditions: what ``baseline``, ``low_light`` and ``texture`` change.

The one table both backends read. A surface at depth ``d`` is mixed with the fog colour in
proportion ``min(1, (d / reach)^4)``, its reach the visibility distance (landmarks: the drawn
distance): clear near, total at the reach, so the fog hides what lies beyond it.
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
    """Metres: where the fog becomes total for what is not a landmark (THOR:
    ``visibilityDistance`` of such objects)."""
    draw_distance: float
    """Metres: where the fog becomes total for landmarks (doorways, the exit); nothing
    farther is drawn."""
    light_factor: float
    """Multiplier on all surface brightness (1.0 = baseline)."""
    fog_color: tuple[int, int, int]
    randomize_palette: bool
    """Whether wall, floor and object colours are drawn at random per episode seed."""


_TABLE: Final[Mapping[str, ConditionParams]] = {
    "baseline": ConditionParams("baseline", 3.25, 7.0, 1.0, (214, 216, 220), False),
    "low_light": ConditionParams("low_light", 3.25, 7.0, 0.5, (56, 56, 60), False),
    "texture": ConditionParams("texture", 3.25, 7.0, 1.0, (214, 216, 220), True),
}


def condition_params(name: str) -> ConditionParams:
    """The parameters of condition ``name``; ConfigError for an unknown name.

    :param name: ``baseline``, ``low_light`` or ``texture``.
    :returns: The condition's :class:`ConditionParams`.
    """
    check_choice("condition", name, CONDITIONS, hint="Pick one of the paper's conditions.")
    return _TABLE[name]
