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
    "builtin-5": {
        "layout": "522fa1ecba82114fe61e836f680c8efdd62cdca36f37b052d1831c06ff7e0957",
        "paper_office": "2407f20637b377faf8accafb8689803cb37456ab7903a39c0629ad0963ebb162",
        "baseline": (
            "4e8abdd888a1e1dd9f9b8741ff103574faf79e8e954bc6dff7fa74775dd765f3",
            "2357834e5fe8afb49f8ec089e8af42d906b977f37eedd4b051c868d1ec000a1c",
        ),
        "low_light": (
            "21fcdd968f030489559cbe2310aab09e49157dbeb1f960159cfdb25a7ca8ceb9",
            "844adada60487252336a557edcc2d7e48b64b3325f7c5e6f55c4d185c20f2c4b",
        ),
        "texture": (
            "0d1cac1bbb979d09a5f61a8712fb99f51abcda1f21f3a2a9a476178b88c12de6",
            "338c96c79ff974ab6565ae2336dac889ffe0752763984054c6c449036fc4e92f",
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
