"""The world stage: the procedural office, its conditions and the simulators that run it.

``episode_world(spec)`` is the world of an episode (the paper's fixed office
``paper_office()`` by default, ``generate_layout(seed)`` under generated layouts);
``make_simulator(backend)`` returns a :class:`Simulator` (``builtin``:
:class:`BuiltinSimulator`, plain numpy; ``ai2thor``: the THOR backend, extra ``thor``);
``ground_truth`` and ``discoverable_ids`` give what the metrics compare against.
``WORLD_VERSION`` keys cassettes. Names are imported on first use (:mod:`pytest_emrd._lazy`).
"""

from pytest_emrd._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(
    __name__,
    {
        "_catalog": ("CATEGORY_OF", "KINDS", "Kind"),
        "_conditions": ("ConditionParams", "condition_params"),
        "_episode": (
            "PAPER_OFFICE_SEED",
            "EpisodeWorld",
            "episode_layout",
            "episode_world",
            "ground_truth",
            "paper_office",
        ),
        "_geometry": ("footprint", "heading_in_spawn_frame", "local_to_world", "to_spawn_frame"),
        "_layout": ("generate_layout",),
        "_model": (
            "Doorway",
            "Layout",
            "Observation",
            "Room",
            "Simulator",
            "VisibleObject",
            "WorldObject",
            "WorldPose",
        ),
        "_registry": ("BACKENDS", "WORLD_VERSION", "make_simulator", "world_version"),
        "_simulator": ("BuiltinSimulator",),
        "_topdown": ("plan_png",),
        "_visibility": ("discoverable_ids",),
    },
)
