"""Builders of small hand-made trajectories, and a small synthetic grid, for metric tests."""

from __future__ import annotations

from collections.abc import Callable, Mapping, Sequence
from pathlib import Path
from typing import Any

import pytest

from pytest_emrd.metrics import EpisodeMetrics, as_episode_metrics
from pytest_emrd.metrics.synthetic import synthetic_grid
from pytest_emrd.rooms import CONFERENCE, ENTRANCE, KITCHEN, OFFICE, ROOM_SLUGS
from pytest_emrd.trajectory import (
    EpisodeSpec,
    GroundTruth,
    GroundTruthObject,
    MapEntry,
    Pose,
    Step,
    Trajectory,
)

#: One step: (room the agent stands in, ids visible, map {label: (type, x, z)}).
StepSpec = tuple[str, Sequence[str], Mapping[str, tuple[str, float, float]]]


def obj(
    object_id: str, room: str = OFFICE, x: float = 0.0, z: float = 0.0, category: str = "salient"
) -> GroundTruthObject:
    """A ground-truth object whose type is its id's prefix (``Chair_2`` -> ``Chair``)."""
    return GroundTruthObject(object_id, object_id.rsplit("_", 1)[0], room, category, x, z)


def build(
    objects: Sequence[GroundTruthObject],
    steps: Sequence[StepSpec],
    *,
    chosen: str | None = None,
    status: str = "terminated",
    discoverable: Sequence[str] | None = None,
    condition: str = "baseline",
    spawn: str = OFFICE,
    episode: int = 0,
    parse_errors: Sequence[int] = (),
    **extra: Any,
) -> Trajectory:
    """A trajectory from compact step specs (1-based ``parse_errors`` reuse the last map)."""
    built: list[Step] = []
    last_map: tuple[MapEntry, ...] = ()
    for t, (room, visible, cog) in enumerate(steps, start=1):
        if t not in parse_errors:
            last_map = tuple(MapEntry(lb, tp, x, z) for lb, (tp, x, z) in cog.items())
        built.append(
            Step(
                index=t,
                pose=Pose(0.0, 0.0, 0.0),
                room=room,
                visible_ids=tuple(sorted(visible)),
                cognitive_map=last_map,
                action="Goto(Doorway_1)",
                success=True,
                feedback="ok",
                parse_error="unreadable" if t in parse_errors else None,
            )
        )
    ids = [o.object_id for o in objects]
    return Trajectory(
        spec=EpisodeSpec("test", condition, ROOM_SLUGS[spawn], episode),
        protocol="test",
        ground_truth=GroundTruth(
            tuple(objects),
            (),
            tuple(sorted(discoverable if discoverable is not None else ids)),
            spawn,
        ),
        steps=tuple(built),
        status=status,
        final_room=built[-1].room if built else spawn,
        chosen_room=chosen,
        chosen_room_raw=chosen,
        **extra,
    )


@pytest.fixture(scope="session")
def make_obj() -> Callable[..., GroundTruthObject]:
    return obj


@pytest.fixture(scope="session")
def make_traj() -> Callable[..., Trajectory]:
    return build


@pytest.fixture(scope="session")
def rooms() -> tuple[str, str, str, str]:
    return OFFICE, CONFERENCE, KITCHEN, ENTRANCE


@pytest.fixture(scope="session")
def small_grid() -> list[Trajectory]:
    """36 synthetic episodes: 3 conditions x 4 spawns x 3 episodes of 50 steps."""
    return synthetic_grid(episodes=3)


@pytest.fixture(scope="session")
def small_grid_metrics(small_grid: list[Trajectory]) -> list[EpisodeMetrics]:
    return as_episode_metrics(small_grid)


#: One committed episode per spawn room, the conference one being issue 12's swapped chairs.
COMMITTED = [("conference", 0), ("office", 3), ("kitchen", 11), ("entrance", 8)]


#: Committed scout episodes in which an invented "exit sign" typed as a door enters a map of
#: one to five entries: it fits the layout as well as the real entries until the map grows.
SPARSE_EARLY = [
    ("conference", 4), ("conference", 10), ("conference", 17),
    ("kitchen", 13), ("kitchen", 14), ("kitchen", 18),
]  # fmt: skip


def _replay(episodes: list[tuple[str, int]]) -> list[Trajectory]:
    """Committed scout baseline episodes, replayed offline from cassettes/scout."""
    from pytest_emrd.agent import load_registry
    from pytest_emrd.episode import protocol_version
    from tests._episodes import agent_runner, run_with_cassette

    root = Path(__file__).resolve().parents[2] / "cassettes"
    runner = agent_runner(load_registry())
    out = []
    for spawn, ep in episodes:
        spec = EpisodeSpec("scout", "baseline", spawn, ep, modality="both")
        run = run_with_cassette(
            spec, runner, cassettes=root, protocol=protocol_version("builtin"), record_mode="none"
        )
        assert run.trajectory.status != "errored", run.trajectory.error
        out.append(run.trajectory)
    return out


@pytest.fixture(scope="session")
def committed() -> list[Trajectory]:
    """Committed scout episodes, one per spawn room (:data:`COMMITTED`)."""
    return _replay(COMMITTED)


@pytest.fixture(scope="session")
def sparse_early() -> list[Trajectory]:
    """The committed episodes of :data:`SPARSE_EARLY`."""
    return _replay(SPARSE_EARLY)
