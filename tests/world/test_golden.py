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
    "builtin-3": {
        "layout": "f7eafb11ad7ad797f8b26098f13d3905ca298ad4bd4cfe0b842c0bdfbacb161f",
        "baseline": (
            "1e580e94506a0c04ba40ad9246954b04504893026e23ed811e305e16ae9e544a",
            "7c7af2c65229fb5c3c195b2ccb264b30ef111658d9a983df0ac5425c0b09dbee",
        ),
        "low_light": (
            "1ce0f97ffa6a95cb59d9e64e9597a688f6992748a51cdc122228aa6e6ab90703",
            "8dedcf8f1c46cb309049e840b45b1d6c5f28999b2703ffa47116553c9ba976a0",
        ),
        "texture": (
            "6c1a9859c8b79a63080b6818870043b22d73622d7fef92cad141d34a9b75cbc7",
            "84025d98fa650e5e1c1cab0718fe3d537c2d41bd1d7f095a5b634ac6aa50fed8",
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
