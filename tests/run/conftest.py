"""Episodes to store: a trajectory with no steps for any spec."""

from __future__ import annotations

from pytest_emrd.trajectory import EpisodeSpec, GroundTruth, Trajectory


def make_trajectory(
    spec: EpisodeSpec, *, status: str = "budget", protocol: str = "p1"
) -> Trajectory:
    gt = GroundTruth(objects=(), rooms=(), discoverable_ids=(), spawn_room="Office")
    return Trajectory(
        spec=spec,
        protocol=protocol,
        ground_truth=gt,
        steps=(),
        status=status,
        final_room="Office",
        error="boom" if status == "errored" else None,
    )
