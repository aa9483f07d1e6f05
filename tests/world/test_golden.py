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

from pytest_emrd._serde import to_dict
from pytest_emrd.world import WORLD_VERSION, Layout, make_simulator, paper_office

GOLDEN = {
    "builtin-6": {
        "layout": "522fa1ecba82114fe61e836f680c8efdd62cdca36f37b052d1831c06ff7e0957",
        "paper_office": "2407f20637b377faf8accafb8689803cb37456ab7903a39c0629ad0963ebb162",
        "baseline": (
            "234adc7b59f3d09a12fcd275e665bd7a0c76669544b83c41030ae53da6ca6175",
            "c45974e824a01e979cfe3e672222e91fcfef7bcc4eb289c2b82d747461ba0cab",
        ),
        "low_light": (
            "b03c1cf40be77df28d21b86f32008a003d0660e1a4f5245dd1ea60e187fe7e98",
            "799525d768a97e674136e27a97e4853434cc3f90ef81cc488e7290a389cae745",
        ),
        "texture": (
            "d09db01aee28ff895f9ed0f69e8898b897115ec7977bb4a48e192f8d008e622f",
            "a4bcb5957de1699bddba82562889f724566c6065a7b80d023a0780b4e8bdee6a",
        ),
    }
}


def _pinned() -> dict:
    if WORLD_VERSION not in GOLDEN:
        pytest.fail(f"WORLD_VERSION={WORLD_VERSION!r} has no golden digests; pin them here.")
    return GOLDEN[WORLD_VERSION]


def test_layout_of_seed_7_is_pinned(office: Layout) -> None:
    text = json.dumps(to_dict(office), sort_keys=True).encode()
    assert hashlib.sha256(text).hexdigest() == _pinned()["layout"]


def test_paper_office_is_pinned() -> None:
    """The fixed office every paper-protocol episode runs in."""
    text = json.dumps(to_dict(paper_office()), sort_keys=True).encode()
    assert hashlib.sha256(text).hexdigest() == _pinned()["paper_office"]


@pytest.mark.parametrize("condition", ["baseline", "low_light", "texture"])
def test_frames_of_the_paper_office_are_pinned(condition: str) -> None:
    sim = make_simulator()
    first = sim.reset(paper_office(), condition, "office", 3)
    second = sim.step("Turn(Right)")
    assert (first.frame_digest, second.frame_digest) == _pinned()[condition]
