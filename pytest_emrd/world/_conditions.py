"""The environmental conditions: what ``baseline``, ``low_light`` and ``texture`` change.

This table is the one definition both backends read (the ai2thor backend takes the
visibility distance and light factor from here).

==========  ==============  ============  =====  ==================  ====================
condition   visibility (m)  drawn to (m)  light  fog at drawn limit  palette
==========  ==============  ============  =====  ==================  ====================
baseline    3.3             7.0           1.0    25 % light haze     catalogue colours
low_light   1.65            3.5           0.5    85 % dark smoke     catalogue colours
texture     3.3             7.0           1.0    25 % light haze     seeded random
==========  ==============  ============  =====  ==================  ====================

Two distances, as in AI2-THOR, whose ``visibilityDistance`` (default 1.5 m) decides which
objects count as *visible* while the frame still draws what is farther:

* the *visibility distance* decides what is reported visible (the ``text`` modality's
  list, the ground-truth visible ids, ``G_base``) and what ``Goto`` may target; landmarks
  (doorways, the exit) are the exception, visible as far as the frame draws them, so an
  agent can always head for the next room (the paper's agent "targets visible elements
  (e.g., doorways)");
* the *drawn distance* decides which objects the frame draws, and the fog.

3.3 m is the largest baseline distance (in 0.1 m steps) at which the paper office meets
the paper's "agents cannot scan rooms from doorways": from 1 m before any doorway, facing
it, at most 3 objects of the next room are visible, and a four-heading sweep at any of a
room's 20 spawn points sees at most 2 objects of other rooms
(``tests/world/test_paper_visibility.py``). Low light halves both distances (the paper:
"reduced by nearly 50 %"); 1.65 m is close to AI2-THOR's 1.5 m default.

Fog grows with the square of the distance: a surface at distance ``d`` is mixed with the
fog colour in proportion ``min(1, fog * (d / drawn)^2)``.

Under ``low_light`` an agent sees objects only within 1.65 m: every room stays reachable
through its doorways, but of the paper office's 41 objects at most 33 can be reached by
chains of ``Goto`` from any spawn (41 under baseline). That is the stress the condition is
meant to apply, not a defect of the layout.
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
    """Fraction of fog colour mixed into a surface at the visibility distance."""
    fog_color: tuple[int, int, int]
    randomize_palette: bool
    """Whether wall, floor and object colours are drawn at random per episode seed."""


_TABLE: Final[Mapping[str, ConditionParams]] = {
    "baseline": ConditionParams("baseline", 3.3, 7.0, 1.0, 0.25, (214, 216, 220), False),
    "low_light": ConditionParams("low_light", 1.65, 3.5, 0.5, 0.85, (56, 56, 60), False),
    "texture": ConditionParams("texture", 3.3, 7.0, 1.0, 0.25, (214, 216, 220), True),
}


def condition_params(name: str) -> ConditionParams:
    """The parameters of condition ``name``; ConfigError for an unknown name."""
    check_choice("condition", name, CONDITIONS, hint="Pick one of the paper's conditions.")
    return _TABLE[name]
