"""The size figure compares the committed cassette with what plain vcrpy records live."""

from __future__ import annotations

from perf.replay import CASSETTES, SAMPLE, live_exchanges, plain_vcrpy_yaml
from pytest_emrd.cassette import SUFFIX, cassette_path


def test_plain_vcrpy_sees_the_jpeg_frames_a_live_run_sends():
    """A replay sends digests (nothing to encode), but plain vcrpy would have recorded the
    live traffic: the size ratio must be measured on JPEG data URLs, not on digests."""
    spec = SAMPLE[0]
    exchanges = live_exchanges(spec)
    bodies = [request.content for request, _ in exchanges]
    assert bodies and all(b"data:image/jpeg;base64," in body for body in bodies)
    plain = len(plain_vcrpy_yaml(exchanges).encode())
    assert plain > 300 * cassette_path(CASSETTES, spec).stat().st_size


def test_the_committed_grid_stays_within_12_kb_per_episode():
    """Every committed cassette, all models: the mean file size per episode. Episodes of the
    paper's world run 44-50 steps (the scout walks into each room's far side, the mimic
    spends its budget), so the bound is 12 KB: about 0.25 KB per recorded exchange."""
    sizes = [p.stat().st_size for p in CASSETTES.rglob(f"*{SUFFIX}")]
    assert len(sizes) >= 320
    assert sum(sizes) / len(sizes) <= 12 * 1024
