"""The world stage: the procedural office, its conditions and the simulators that run it.

``generate_layout(seed)`` builds the office; ``make_simulator(backend)`` returns a
:class:`Simulator` (``builtin``: :class:`BuiltinSimulator`, pure numpy; ``ai2thor``: the
THOR backend, extra ``thor``); ``ground_truth`` and ``discoverable_ids`` give what the
metrics compare against. ``WORLD_VERSION`` keys cassettes.
"""

from pytest_emrd.world._catalog import CATEGORY_OF, KINDS, Kind
from pytest_emrd.world._conditions import ConditionParams, condition_params
from pytest_emrd.world._geometry import footprint, heading_in_spawn_frame, to_spawn_frame
from pytest_emrd.world._layout import generate_layout
from pytest_emrd.world._model import (
    Doorway,
    Layout,
    Observation,
    Room,
    Simulator,
    VisibleObject,
    WorldObject,
    WorldPose,
)
from pytest_emrd.world._registry import BACKENDS, make_simulator, world_version
from pytest_emrd.world._simulator import BuiltinSimulator
from pytest_emrd.world._truth import ground_truth
from pytest_emrd.world._version import WORLD_VERSION
from pytest_emrd.world._visibility import discoverable_ids

__all__ = [
    "BACKENDS",
    "CATEGORY_OF",
    "KINDS",
    "WORLD_VERSION",
    "BuiltinSimulator",
    "ConditionParams",
    "Doorway",
    "Kind",
    "Layout",
    "Observation",
    "Room",
    "Simulator",
    "VisibleObject",
    "WorldObject",
    "WorldPose",
    "condition_params",
    "discoverable_ids",
    "footprint",
    "generate_layout",
    "ground_truth",
    "heading_in_spawn_frame",
    "make_simulator",
    "to_spawn_frame",
    "world_version",
]
