"""The environmental conditions: what ``baseline``, ``low_light`` and ``texture`` change.

The one table both backends read. A surface at distance ``d`` is mixed with the fog colour
in proportion ``min(1, fog * (d / drawn)^2)``. Why two distances, why 3.3 m, and what low
light costs: ``docs/interpretation/world.md`` ("Visibility").
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
    """Metres: objects farther than this are not reported visible (nor ``Goto`` targets);
    landmarks count as visible up to :attr:`draw_distance`."""
    draw_distance: float
    """Metres: objects farther than this are not drawn in the frame; the fog's scale."""
    light_factor: float
    """Multiplier on all surface brightness (1.0 = baseline)."""
    fog: float
    """Fraction of fog colour mixed into a surface at the drawn distance."""
    fog_color: tuple[int, int, int]
    randomize_palette: bool
    """Whether wall, floor and object colours are drawn at random per episode seed."""


_TABLE: Final[Mapping[str, ConditionParams]] = {
    "baseline": ConditionParams("baseline", 3.3, 7.0, 1.0, 0.25, (214, 216, 220), False),
    "low_light": ConditionParams("low_light", 1.65, 3.5, 0.5, 0.85, (56, 56, 60), False),
    "texture": ConditionParams("texture", 3.3, 7.0, 1.0, 0.25, (214, 216, 220), True),
}


def condition_params(name: str) -> ConditionParams:
    """The parameters of condition ``name``; ConfigError for an unknown name.

    :param name: ``baseline``, ``low_light`` or ``texture``.
    :returns: The condition's :class:`ConditionParams`.
    """
    check_choice("condition", name, CONDITIONS, hint="Pick one of the paper's conditions.")
    return _TABLE[name]
