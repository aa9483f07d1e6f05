"""The environmental conditions: what ``baseline``, ``low_light`` and ``texture`` change.

This table is the one definition both backends read (the ai2thor backend takes the
visibility distance and light factor from here).

==========  ==============  =====  ====================  ===============================
condition   visibility (m)  light  fog at the limit      palette
==========  ==============  =====  ====================  ===============================
baseline    7.0             1.0    25 % light haze       catalogue colours
low_light   3.5             0.5    85 % dark smoke       catalogue colours
texture     7.0             1.0    25 % light haze       seeded random per episode
==========  ==============  =====  ====================  ===============================

Fog grows with the square of the distance: a surface at distance ``d`` is mixed with the
fog colour in proportion ``min(1, fog * (d / visibility)^2)``.

Under ``low_light`` an agent can lose its way: in a large room the far doorway may lie
beyond 3.5 m of every spot ``Goto`` can reach, so a room that is reachable under
``baseline`` can stay out of reach (about 5 % of seed/spawn pairs). That is the stress the
condition is meant to apply, not a defect of the layout.
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
    """Metres: objects farther than this are neither reported visible nor drawn."""
    light_factor: float
    """Multiplier on all surface brightness (1.0 = baseline)."""
    fog: float
    """Fraction of fog colour mixed into a surface at the visibility distance."""
    fog_color: tuple[int, int, int]
    randomize_palette: bool
    """Whether wall, floor and object colours are drawn at random per episode seed."""


_TABLE: Final[Mapping[str, ConditionParams]] = {
    "baseline": ConditionParams("baseline", 7.0, 1.0, 0.25, (214, 216, 220), False),
    "low_light": ConditionParams("low_light", 3.5, 0.5, 0.85, (56, 56, 60), False),
    "texture": ConditionParams("texture", 7.0, 1.0, 0.25, (214, 216, 220), True),
}


def condition_params(name: str) -> ConditionParams:
    """The parameters of condition ``name``; ConfigError for an unknown name."""
    check_choice("condition", name, CONDITIONS, hint="Pick one of the paper's conditions.")
    return _TABLE[name]
