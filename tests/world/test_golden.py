"""Golden digests: the layout and the frames of one episode, pinned to WORLD_VERSION.

Cassettes key frames by these pixel digests. If this test fails, the world changed what
it draws or generates: bump ``WORLD_VERSION`` (recorded cassettes become stale) and pin
the new digests under the new version. Pixels are computed with exact IEEE arithmetic
and integer colour stages, so these digests hold on every machine and numpy version.
"""

from __future__ import annotations

import hashlib
import json

import pytest

from pytest_emrd.world import WORLD_VERSION, Layout, make_simulator

GOLDEN = {
    "builtin-2": {
        "layout": "f7eafb11ad7ad797f8b26098f13d3905ca298ad4bd4cfe0b842c0bdfbacb161f",
        "baseline": (
            "709aab3ea5e35d99a52bc5e6e51d9b4a85e5a2ae21847c4b43a361d979348eeb",
            "e2e257bb2b074f026efd92913c534322885a2f559d82f366d088b63824ff78ea",
        ),
        "low_light": (
            "f4f26be2e06d06010352c84b2fde42989c5690b23234b6b0763d37162148c24e",
            "fb2439b4a728a927f1ca05eeea3641a0702c5394adf32cb431d3f837953db3ff",
        ),
        "texture": (
            "9b31a5657d1b915e357f5ff14d7b1d5292f985263be0c1a0e7420c9b63194a84",
            "548d2605d33444f023fd2d29cac7f0bf8dae156f99f97687e36cf5250808b7ad",
        ),
    }
}


def _pinned() -> dict:
    if WORLD_VERSION not in GOLDEN:
        pytest.fail(f"WORLD_VERSION={WORLD_VERSION!r} has no golden digests; pin them here.")
    return GOLDEN[WORLD_VERSION]


def test_layout_of_seed_7_is_pinned(office: Layout) -> None:
    text = json.dumps(office.to_dict(), sort_keys=True).encode()
    assert hashlib.sha256(text).hexdigest() == _pinned()["layout"]


@pytest.mark.parametrize("condition", ["baseline", "low_light", "texture"])
def test_frames_of_seed_7_are_pinned(office: Layout, condition: str) -> None:
    sim = make_simulator()
    first = sim.reset(office, condition, "office", 3)
    second = sim.step("Turn(Right)")
    assert (first.frame_digest, second.frame_digest) == _pinned()[condition]
