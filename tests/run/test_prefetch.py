"""--emrd-concurrency: live episodes recorded in threads, each once, each to its own cassette."""

from __future__ import annotations

from pathlib import Path

from pytest_emrd.agent import OpenAICompatibleClient, load_registry
from pytest_emrd.episode import protocol_version, run_episode
from pytest_emrd.reference import ReferenceServer
from pytest_emrd.run import Prefetcher, ResultsStore, resolve_settings, start_prefetch
from pytest_emrd.trajectory import EpisodeSpec
from tests._episodes import run_with_cassette, traffic

SPECS = [
    EpisodeSpec("scout", condition, spawn, 0, modality="both", max_steps=3)
    for condition in ("baseline", "texture")
    for spawn in ("office", "kitchen")
]


def _recorder(root: Path, base_url: str, calls: list[EpisodeSpec]):
    registry = load_registry()
    client = OpenAICompatibleClient(registry.get("scout"), base_url=base_url, require_key=False)

    def compute(spec: EpisodeSpec):
        calls.append(spec)
        return run_with_cassette(
            spec,
            lambda s, live: run_episode(s, registry=registry, client=client),
            cassettes=root / "cassettes",
            protocol=protocol_version(),
            record_mode="all",
        )

    return compute


def test_concurrent_recording_writes_the_cassettes_a_lone_episode_writes(tmp_path: Path):
    calls: list[EpisodeSpec] = []
    with ReferenceServer(latency_s=0.05) as server:
        together = _recorder(tmp_path / "together", server.base_url, calls)
        run_dir = tmp_path / "together" / "run"
        store = ResultsStore(run_dir, session="s", protocol=protocol_version())
        prefetcher = Prefetcher(store, together, SPECS, workers=4)
        prefetcher.wait()
        prefetcher.close()
        alone = _recorder(tmp_path / "alone", server.base_url, [])
        for spec in SPECS:
            alone(spec)
    assert sorted(calls, key=str) == sorted(SPECS, key=str), "each episode computed once"
    together_files = sorted((tmp_path / "together" / "cassettes").rglob("*.json.xz"))
    alone_files = sorted((tmp_path / "alone" / "cassettes").rglob("*.json.xz"))
    assert [p.relative_to(tmp_path / "together") for p in together_files] == [
        p.relative_to(tmp_path / "alone") for p in alone_files
    ]
    assert len(together_files) == len(SPECS)
    assert [traffic(p.read_bytes()) for p in together_files] == [
        traffic(p.read_bytes()) for p in alone_files
    ]
    for spec in SPECS:
        assert store.get_or_compute(spec, together).trajectory.status != "errored"
    assert len(calls) == len(SPECS), "stored episodes are read back, not recomputed"


def test_an_episode_locked_elsewhere_is_skipped_not_waited_for(tmp_path: Path):
    store = ResultsStore(tmp_path, session="s", protocol="p")
    calls: list[EpisodeSpec] = []
    with store.lock(SPECS[0]):
        prefetcher = Prefetcher(store, calls.append, SPECS[:1], workers=1)
        prefetcher.wait()
    prefetcher.close()
    assert calls == []


def test_no_prefetch_for_replays_or_one_at_a_time(tmp_path: Path):
    def settings(**cli):
        return resolve_settings(cli, {}, rootdir=tmp_path, env={})

    store = ResultsStore(tmp_path / "run", session="s", protocol="p")
    assert start_prefetch(settings(concurrency="1"), store, print, SPECS) is None
    replay = settings(concurrency="4", record_mode="none")
    assert start_prefetch(replay, store, print, SPECS) is None
