"""Re-expressing a model's cognitive maps in another frame (for invariance checks).

Every coordinate a model writes is in a frame of its own choosing; the metrics must not
care which. :func:`reframe` moves every map entry of an episode by one rigid motion (and,
on request, a mirror), leaving the engine's ground truth and poses alone, so a caller can
check that each metric is unchanged (``emrd validate`` and the property tests do).
"""

from __future__ import annotations

import dataclasses
import math

import numpy as np

from pytest_emrd.trajectory import MapEntry, Trajectory


def reframe(
    traj: Trajectory, theta: float, dx: float, dz: float, *, mirror: bool = False
) -> Trajectory:
    """``traj`` with every cognitive-map coordinate ``p`` replaced by ``R(theta) M p + t``.

    ``R(theta)`` rotates by ``theta`` radians, ``t = (dx, dz)`` translates, ``M`` mirrors
    ``x -> -x`` when ``mirror`` (an improper motion, which no metric forgives). One motion
    for the whole episode, as a model that picked another origin and heading would write.
    Steps that share a map object (a parse failure repeats the last map) still share it.
    """
    c, s = math.cos(theta), math.sin(theta)
    sign = -1.0 if mirror else 1.0
    moved: dict[int, tuple[MapEntry, ...]] = {}
    steps = []
    for step in traj.steps:
        key = id(step.cognitive_map)
        if key not in moved:
            moved[key] = tuple(
                dataclasses.replace(
                    e, x=c * sign * e.x - s * e.z + dx, z=s * sign * e.x + c * e.z + dz
                )
                for e in step.cognitive_map
            )
        steps.append(dataclasses.replace(step, cognitive_map=moved[key]))
    return dataclasses.replace(traj, steps=tuple(steps))


def random_reframe(traj: Trajectory, rng: np.random.Generator) -> Trajectory:
    """:func:`reframe` with a proper motion drawn from ``rng``: a uniform heading and an
    origin uniform in ``[-100, 100]^2`` metres."""
    theta = float(rng.uniform(0.0, 2.0 * math.pi))
    dx, dz = (float(v) for v in rng.uniform(-100.0, 100.0, 2))
    return reframe(traj, theta, dx, dz)
