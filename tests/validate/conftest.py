"""Hand-built trajectories with known memory, grounding and exploration, for the check rows.

``build`` takes, per step, the room the agent stands in, the object ids in view and the
object ids its map holds (entries at their true positions, labelled by id), so every spell,
load and forgetting event is known by construction.
"""

from __future__ import annotations

from collections.abc import Callable, Sequence

import pytest

from pytest_emrd.rooms import ROOM_NAMES
from pytest_emrd.trajectory import (
    EpisodeSpec,
    GroundTruth,
    GroundTruthObject,
    MapEntry,
    Pose,
    RoomOutline,
    Step,
    Trajectory,
)

#: Ten objects per room, spread on a grid; ids ``Chair_1`` .. ``Chair_40``.
OBJECTS = tuple(
    GroundTruthObject(f"Chair_{i + 1}", "Chair", ROOM_NAMES[i // 10], "salient",
                      float(i % 7), float(i // 7))
    for i in range(40)
)  # fmt: skip
_BY_ID = {o.object_id: o for o in OBJECTS}
_OUTLINES = tuple(RoomOutline(r, ((0, 0), (1, 0), (1, 1))) for r in ROOM_NAMES)

Frame = tuple[str, Sequence[str], Sequence[str]]
Builder = Callable[..., Trajectory]


def ids(*numbers: int) -> list[str]:
    return [f"Chair_{n}" for n in numbers]


def build_trajectory(
    frames: Sequence[Frame],
    *,
    model: str = "hand",
    condition: str = "baseline",
    spawn: str = "office",
    episode: int = 0,
    chosen: str | None = None,
    discoverable: Sequence[str] | None = None,
) -> Trajectory:
    steps = tuple(
        Step(
            index=t,
            pose=Pose(0.0, 0.0, 0.0),
            room=room,
            visible_ids=tuple(sorted(visible)),
            cognitive_map=tuple(
                MapEntry(oid, "Chair", _BY_ID[oid].x, _BY_ID[oid].z) for oid in held
            ),
            action="Turn(Right)",
            success=True,
            feedback="ok",
        )
        for t, (room, visible, held) in enumerate(frames, start=1)
    )
    truth = GroundTruth(
        OBJECTS,
        _OUTLINES,
        tuple(sorted(discoverable if discoverable is not None else _BY_ID)),
        frames[0][0],
    )
    return Trajectory(
        spec=EpisodeSpec(model, condition, spawn, episode, modality="text"),
        protocol="hand-1",
        ground_truth=truth,
        steps=steps,
        status="terminated" if chosen else "budget",
        final_room=frames[-1][0],
        chosen_room=chosen,
        chosen_room_raw=chosen,
    )


def window_frames(k: int, n_objects: int = 30, extra: int = 5) -> list[Frame]:
    """One new object in view per step; the map keeps the k most recently seen (LRU)."""
    frames: list[Frame] = []
    held: list[str] = []
    for i in range(1, n_objects + extra + 1):
        visible = ids(i) if i <= n_objects else []
        held = [*[h for h in held if h not in visible], *visible][-k:]
        frames.append((ROOM_NAMES[0], visible, list(held)))
    return frames


@pytest.fixture
def build() -> Builder:
    return build_trajectory


@pytest.fixture
def window() -> Callable[..., list[Frame]]:
    return window_frames


@pytest.fixture
def chairs() -> Callable[..., list[str]]:
    return ids
