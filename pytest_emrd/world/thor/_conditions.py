"""The two numbers this backend needs from a condition, read from the shared world table.

:func:`pytest_emrd.world.condition_params` is the one definition of what ``baseline``,
``low_light`` and ``texture`` mean; this adapter only names the fields THOR consumes, so
the builtin and the ai2thor backends can never disagree about a condition.
"""

from __future__ import annotations

from dataclasses import dataclass


@dataclass(frozen=True)
class ThorCondition:
    """What a condition changes in THOR."""

    visibility_distance: float
    """Metres; how far an object THOR reports ``visible`` counts as visible (horizontally, to
    the nearest point of its bounding box)."""
    draw_distance: float
    """Metres; THOR's ``visibilityDistance``, and how far landmarks (doorways, the exit) count
    as visible: the builtin world's two distances (:mod:`pytest_emrd.world._conditions`)."""
    light_factor: float
    """Multiplier on every house light's intensity (1.0 = baseline)."""
    randomize_materials: bool
    """Whether reset issues ``RandomizeMaterials`` + ``RandomizeColors``."""


def thor_condition(name: str) -> ThorCondition:
    """The THOR settings of condition ``name`` (raises ConfigError for an unknown name)."""
    from pytest_emrd.world._conditions import condition_params

    params = condition_params(name)
    return ThorCondition(
        visibility_distance=float(params.visibility_distance),
        draw_distance=float(params.draw_distance),
        light_factor=float(params.light_factor),
        randomize_materials=params.randomize_palette,
    )
