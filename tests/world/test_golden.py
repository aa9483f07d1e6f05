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
    "builtin-7": {
        "layout": "522fa1ecba82114fe61e836f680c8efdd62cdca36f37b052d1831c06ff7e0957",
        "paper_office": "2407f20637b377faf8accafb8689803cb37456ab7903a39c0629ad0963ebb162",
        "baseline": (
            "80c8946e927d6a302d79044fad645927f90aa508a959c63215c45813492800c8",
            "d4eae113a4098a3898c18f8244a560d2a0858b7f78c1a17c65b7fca123ebbbc9",
        ),
        "low_light": (
            "220dad75fd159f454aa792554c7aa8f251427bfc8a2d08872b26043168b55322",
            "25d8a7f0d1be1d429773dae86b2ed7945ece2a385b1af2fab64b8a23ebdaafda",
        ),
        "texture": (
            "9f81cf66966f5be283adfd1a343a65527b70e2eeef2d6cb395a35c1013b52b04",
            "fb1cc0be3755091e7d8573029acb26761def4a3c10b22f6b2c2c2cb4b2046ee4",
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
