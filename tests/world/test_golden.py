"""Golden digests: the paper's office, a generated layout and the frames of one episode,
pinned to WORLD_VERSION.

Cassettes key frames by these pixel digests. If this test fails, the world changed what
it draws or generates: bump ``WORLD_VERSION`` (recorded cassettes become stale) and pin
the new digests under the new version. Pixels are computed with exact IEEE arithmetic
and integer colour stages, so these digests hold on every machine and numpy version.
"""

from __future__ import annotations

import hashlib
import json

import pytest

from pytest_emrd.world import WORLD_VERSION, Layout, make_simulator, paper_office

GOLDEN = {
    "builtin-4": {
        "layout": "522fa1ecba82114fe61e836f680c8efdd62cdca36f37b052d1831c06ff7e0957",
        "paper_office": "2407f20637b377faf8accafb8689803cb37456ab7903a39c0629ad0963ebb162",
        "baseline": (
            "64d223ae0409244752a168b81500abc64ac9e053edab714ed1eee7dd6c5a0dfe",
            "a8ff5e3f524970cffd9999448be6b0ab50f35ce23ad7b23aeba869e3382bb03f",
        ),
        "low_light": (
            "f05b231ecb95c6934143ebef68bc03568aa592dbddb97f1ed99b54b60770d992",
            "29f1607f0150b1e7dd34ce5a12356126769dc9f72ac2d8807af08847b45c5b01",
        ),
        "texture": (
            "29d1806d562629c8a7eba768d9e24f1c23daa0bbfd10e8488e57080347605c0f",
            "a86be10bdc4db88a4cfba838de569e25d9b5f51d6dd6d0b1e1a4f34038e334dc",
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


def test_paper_office_is_pinned() -> None:
    """The fixed office every paper-protocol episode runs in."""
    text = json.dumps(paper_office().to_dict(), sort_keys=True).encode()
    assert hashlib.sha256(text).hexdigest() == _pinned()["paper_office"]


@pytest.mark.parametrize("condition", ["baseline", "low_light", "texture"])
def test_frames_of_the_paper_office_are_pinned(condition: str) -> None:
    sim = make_simulator()
    first = sim.reset(paper_office(), condition, "office", 3)
    second = sim.step("Turn(Right)")
    assert (first.frame_digest, second.frame_digest) == _pinned()[condition]
