"""The world stage: the procedural office, its conditions and the simulators that run it.

``episode_world(spec)`` is the world of an episode (the paper's fixed office
``paper_office()`` by default, ``generate_layout(seed)`` under generated layouts);
``make_simulator(backend)`` returns a :class:`Simulator` (``builtin``:
:class:`BuiltinSimulator`, numpy with a numba pixel kernel; ``ai2thor``: the THOR backend,
extra ``thor``); ``ground_truth`` and ``discoverable_ids`` give what the
metrics compare against. ``WORLD_VERSION`` keys cassettes.
"""

from pytest_emrd.world._catalog import CATEGORY_OF, KINDS, Kind
from pytest_emrd.world._conditions import ConditionParams, condition_params
from pytest_emrd.world._episode import (
    PAPER_OFFICE_SEED,
    EpisodeWorld,
    episode_layout,
    episode_world,
    paper_office,
)
from pytest_emrd.world._geometry import (
    footprint,
    heading_in_spawn_frame,
    local_to_world,
    to_spawn_frame,
)
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
    "PAPER_OFFICE_SEED",
    "WORLD_VERSION",
    "BuiltinSimulator",
    "ConditionParams",
    "Doorway",
    "EpisodeWorld",
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
    "episode_layout",
    "episode_world",
    "footprint",
    "generate_layout",
    "ground_truth",
    "heading_in_spawn_frame",
    "local_to_world",
    "make_simulator",
    "paper_office",
    "to_spawn_frame",
    "world_version",
]
