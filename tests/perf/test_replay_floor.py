"""The floor figure: httpx and vcrpy alone answering a replay's own requests."""

from __future__ import annotations

import re

from perf.replay import SAMPLE, _httpx_vcrpy_floor_ratio, live_exchanges


def test_the_floor_sends_the_digests_a_replay_sends():
    """The floor times the requests a replay really makes: frames as pixel digests, no JPEG
    (timing JPEG windows would inflate the floor)."""
    bodies = [request.content for request, _ in live_exchanges(SAMPLE[0], as_sent_live=False)]
    assert bodies and not any(b"data:image/jpeg" in body for body in bodies)
    assert all(re.search(rb'"pixels:[0-9a-f]{64}"', body) for body in bodies)


def test_the_floor_is_answered_by_vcrpy_and_costs_more_than_the_world_alone():
    """Every request is answered from vcrpy's files (nothing listens on the reference URL
    here: a request that escaped would raise), and the floor is a ratio above 1."""
    assert _httpx_vcrpy_floor_ratio(SAMPLE[:2], repeat=1, warmup=1) > 1.0
