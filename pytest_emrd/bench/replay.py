"""``emrd bench replay``: what replaying cassettes costs, in time and bytes.

* ``replay.grid_240_s`` — wall time of ``pytest benchmarks -n 2 --emrd-record-mode=none``
  over the full reference grid (scout x 3 conditions x 4 spawns x 20 episodes, committed
  cassettes, gates included), in a fresh run directory. Target 60 s.
* ``replay.cassette_kb_per_episode`` — mean size of the committed scout cassettes; and
  ``replay.cassette_kb_per_50_steps`` — the size of a full 50-step episode, predicted by a
  least-squares line of cassette size on request count over the committed grid (episodes run
  8 to 50 steps). Scaling each file by ``50 / requests`` would count the per-episode fixed part
  (system prompt, first frame) once per step; the line separates the fixed part from the
  per-step part. Target 15 KB.
* ``replay.size_ratio_vs_plain_vcrpy`` — the same episodes recorded side by side with plain
  vcrpy (YAML, base64 frames kept, no redaction) and with EMRD cassettes; total plain bytes
  over total EMRD bytes. Target 500.
* ``replay.step_overhead_ms`` — per request of a replayed episode: redaction of the live
  body (frames in it), vcrpy matching, response rebuild and JSON parse in httpx; no world,
  no rendering, no agent. The live request bodies are captured once from a real episode.
  Target 5 ms.
"""

from __future__ import annotations

import statistics
import subprocess
import sys
import tempfile
from pathlib import Path
from typing import Any

import httpx
import numpy as np
import vcr

from pytest_emrd.bench import Figure, median_seconds
from pytest_emrd.cassette import cassette_path, episode_cassette, run_with_cassette
from pytest_emrd.trajectory import EpisodeSpec

ROOT = Path(__file__).resolve().parents[2]
CASSETTES = ROOT / "cassettes"
#: One episode per spawn room under each condition (12 episodes, fixed, not picked by size).
SIDE_BY_SIDE = tuple(
    EpisodeSpec("scout", condition, spawn, 0, modality="both")
    for condition in ("baseline", "low_light", "texture")
    for spawn in ("office", "conference", "kitchen", "entrance")
)


class _Capture(httpx.BaseTransport):
    """A real HTTP transport that keeps every request it sends."""

    def __init__(self) -> None:
        self.inner = httpx.HTTPTransport()
        self.requests: list[httpx.Request] = []

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        request.read()
        self.requests.append(request)
        return self.inner.handle_request(request)


def _runner() -> Any:
    from pytest_emrd.agent import load_registry
    from pytest_emrd.cassette import agent_runner

    return agent_runner(load_registry())


def _protocol() -> str:
    from pytest_emrd.episode import protocol_version

    return protocol_version()


def _grid_seconds(repeat: int) -> float:
    def replay() -> None:
        with tempfile.TemporaryDirectory() as tmp:
            cmd = [sys.executable, "-m", "pytest", "benchmarks", "-n", "2", "-q"]
            cmd += ["-p", "no:cacheprovider", "--emrd-record-mode=none", f"--emrd-results={tmp}"]
            done = subprocess.run(cmd, cwd=ROOT, capture_output=True, text=True, check=False)
            if done.returncode != 0:
                raise RuntimeError(f"replay of the reference grid failed:\n{done.stdout[-3000:]}")

    return median_seconds(replay, repeat=repeat, warmup=0)


def _committed_sizes() -> tuple[float, float, int]:
    from pytest_emrd.cassette import decode

    paths = sorted((CASSETTES / "scout").rglob("*.yaml.gz"))
    if not paths:
        raise RuntimeError(f"no scout cassettes under {CASSETTES}; record them first")
    sizes = [p.stat().st_size / 1024 for p in paths]
    requests = [len(decode(p.read_bytes()).requests) for p in paths]
    slope, intercept = np.polyfit(requests, sizes, 1)
    return statistics.fmean(sizes), float(intercept + 50 * slope), len(paths)


def _side_by_side_ratio() -> float:
    runner, protocol = _runner(), _protocol()
    plain = ours = 0
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)
        for spec in SIDE_BY_SIDE:
            path = root / "plain" / f"{spec.case_id}.yaml"
            with vcr.VCR(record_mode="all").use_cassette(str(path)):
                runner(spec, live=True)
            plain += path.stat().st_size
            run_with_cassette(spec, runner, cassettes=root, protocol=protocol, record_mode="all")
            ours += cassette_path(root, spec).stat().st_size
    return plain / ours


def _step_overhead_ms(repeat: int) -> float:
    from pytest_emrd.agent import OpenAICompatibleClient, load_registry
    from pytest_emrd.agent.reference import reference_base_url
    from pytest_emrd.episode import run_episode

    spec = EpisodeSpec("scout", "baseline", "office", 0, modality="both")
    registry, protocol = load_registry(), _protocol()
    capture = _Capture()
    with tempfile.TemporaryDirectory() as tmp:
        root = Path(tmp)

        def record(s: EpisodeSpec, *, live: bool) -> Any:
            config = registry.get(s.model)
            client = OpenAICompatibleClient(
                config, base_url=reference_base_url(), transport=capture
            )
            try:
                return run_episode(s, registry=registry, client=client)
            finally:
                client.close()

        run_with_cassette(spec, record, cassettes=root, protocol=protocol, record_mode="all")
        live = [(r.method, str(r.url), dict(r.headers), r.content) for r in capture.requests]

        http = httpx.Client()  # created once: client start-up is the agent's cost, not replay's

        def replay() -> None:
            with episode_cassette(
                cassette_path(root, spec),
                protocol=protocol,
                record_mode="none",
                matching="strict",
                rerecord_command="(bench)",
            ):
                for method, url, headers, body in live:
                    http.request(method, url, headers=headers, content=body).json()

        seconds = median_seconds(replay, repeat=repeat)
        http.close()
    return seconds / len(live) * 1000


def run(*, repeat: int) -> list[Figure]:
    overhead = _step_overhead_ms(repeat)
    ratio = _side_by_side_ratio()
    kb, kb_50, count = _committed_sizes()
    grid = _grid_seconds(repeat)
    return [
        Figure("replay.grid_240_s", grid, "s", 60.0, repeat),
        Figure("replay.cassette_kb_per_episode", kb, "KB", 15.0, count),
        Figure("replay.cassette_kb_per_50_steps", kb_50, "KB", 15.0, count),
        Figure("replay.size_ratio_vs_plain_vcrpy", ratio, "ratio", 500.0, len(SIDE_BY_SIDE)),
        Figure("replay.step_overhead_ms", overhead, "ms", 5.0, repeat),
    ]
