"""``python -m perf live``: recording episodes concurrently against a slow remote model.

* ``live.concurrency_16_vs_floor`` — 64 ``scout`` episodes (at most 6 steps each, the 64
  first cases of the grid) recorded by one process with ``--emrd-concurrency 16``'s
  machinery (results store, per-thread cassettes, record mode ``all``) against a reference
  server that adds 0.5 s to every call. Wall time over the latency floor, the shortest time
  any schedule of 16 concurrent episodes could take: ``max(sum of calls x 0.5 s / 16,
  the longest episode's calls x 0.5 s)``. Everything else (world, rendering, agent,
  redaction, cassette writing) must hide behind the waits. Target 1.3.
"""

from __future__ import annotations

import statistics
import tempfile
import time
from pathlib import Path
from typing import Any

from perf import Figure, run_with_cassette
from pytest_emrd.trajectory import CONDITIONS, EpisodeSpec

LATENCY_S = 0.5
CONCURRENCY = 16
EPISODES = 64
MAX_STEPS = 6
SPECS = tuple(
    EpisodeSpec("scout", condition, spawn, episode, modality="both", max_steps=MAX_STEPS)
    for episode in range(EPISODES)
    for condition in CONDITIONS
    for spawn in ("office", "conference", "kitchen", "entrance")
)[:EPISODES]


def _record_all(root: Path) -> float:
    """Wall time / latency floor of recording :data:`SPECS` under ``root``."""
    from pytest_emrd.agent import OpenAICompatibleClient, load_registry
    from pytest_emrd.episode import protocol_version, run_episode
    from pytest_emrd.reference import ReferenceServer
    from pytest_emrd.run import Prefetcher, ResultsStore

    registry, protocol = load_registry(), protocol_version()
    with ReferenceServer(registry=registry, latency_s=LATENCY_S) as server:
        client = OpenAICompatibleClient(
            registry.get("scout"), base_url=server.base_url, require_key=False
        )

        def run(spec: EpisodeSpec, *, live: bool) -> Any:
            return run_episode(spec, registry=registry, client=client)

        def compute(spec: EpisodeSpec) -> Any:
            return run_with_cassette(
                spec, run, cassettes=root / "cassettes", protocol=protocol, record_mode="all"
            )

        store = ResultsStore(root / "run", session="bench", protocol=protocol)
        start = time.perf_counter()
        prefetcher = Prefetcher(store, compute, SPECS, workers=CONCURRENCY)
        try:
            prefetcher.wait()
        finally:
            prefetcher.close()
        wall = time.perf_counter() - start
        client.close()
    calls = [len(store.get_or_compute(s, compute).trajectory.steps) for s in SPECS]
    floor = max(sum(calls) * LATENCY_S / CONCURRENCY, max(calls) * LATENCY_S)
    return wall / floor


def run(*, repeat: int, warmup: int) -> list[Figure]:
    ratios = []
    for i in range(warmup + repeat):
        with tempfile.TemporaryDirectory() as tmp:
            ratio = _record_all(Path(tmp))
        if i >= warmup:
            ratios.append(ratio)
    return [Figure("live.concurrency_16_vs_floor", statistics.median(ratios), "ratio", 1.3, repeat)]
