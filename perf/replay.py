"""``python -m perf replay``: what replaying cassettes costs, in time and bytes.

* ``replay.grid_240_s`` — wall time of ``pytest benchmarks -n 2 --emrd-record-mode=none``
  over the full reference grid (scout x 3 conditions x 4 spawns x 20 episodes, committed
  cassettes, gates included), in a fresh run directory. Target 20 s. And
  ``replay.resume_240_s``: the same command again on that finished run directory (every
  episode checked against the results store from its head line, every gate evaluated again
  over the metrics kept when the first command measured each episode). Target 3 s.
  ``replay.grid_240_cpu_s`` and ``replay.resume_240_cpu_s``: the CPU time of those
  commands (controller and workers), which other load on the machine stretches less than
  wall time. All under Python's default bytecode policy (:func:`~perf.python_env`; warm: one
  untimed round first fills the cache, as on a user's machine from the second run on);
  ``replay.resume_240_nobytecode_s``,
  no target, is the resume again with ``PYTHONDONTWRITEBYTECODE=1``, where every one of the
  three pytest processes compiles our package and rewrites the plugin packages again.
* ``replay.vs_world_ratio`` — replaying :data:`SAMPLE` (12 committed episodes, one per
  condition and spawn) through their cassettes, as the plugin does (cassette load, the whole
  episode loop, redaction, matching), over the world alone doing the same work: layout,
  reset, ground truth and the same actions, with the same per-step reads. Both run warm
  (one warm-up each: code loaded) and both start with the world's view
  digests and shade tables forgotten, as in a fresh worker (a warm world knows every view of
  the sample and draws none: the ratio would then compare the replay with almost nothing),
  so the world draws each view of the sample once on both sides and only the replay's cost
  remains above 1. Target 1.2. And ``replay.httpx_vcrpy_floor_vs_world_ratio``, no target:
  the same ratio with the replay replaced by httpx and vcrpy alone answering the sample's
  requests (the cheapest matching vcrpy allows; no cassette load, redaction, parsing or agent),
  so the part of ``vs_world_ratio`` that is the real client and vcrpy is shown apart from ours.
* ``replay.cassette_kb_per_episode`` — mean size of the committed scout cassettes; and
  ``replay.cassette_kb_per_50_steps`` — the size of a full 50-step episode, predicted by a
  least-squares line of cassette size on request count over the committed grid (episodes run
  8 to 50 steps). Scaling each file by ``50 / requests`` would count the per-episode fixed part
  (system prompt, first frame) once per step; the line separates the fixed part from the
  per-step part. Target 15 KB.
* ``replay.size_ratio_vs_plain_vcrpy`` — the committed cassettes of :data:`SIZE_SAMPLE` (24
  episodes) against what plain vcrpy stores for the same traffic (YAML, base64 frames kept,
  no redaction): each episode is replayed from its cassette while the HTTP requests the agent
  really sends and the responses it gets are captured, then written with vcrpy's own YAML
  serialiser. Total plain bytes over total committed bytes. Plain vcrpy would
  also keep the server's volatile response headers, which replay does not reproduce: the
  ratio is, if anything, low. Target 500.
* ``replay.step_overhead_ms`` — per request of a replayed episode, through the real client:
  body encoding, redaction, vcrpy matching, response rebuild and JSON parse (a replay sends
  each frame as its pixel digest: no JPEG, no frame registration); no world, no agent logic.
  The messages are captured once from a real replay (each message the same object while it
  stays in the window, as the loop sends them); every repetition starts with the redaction
  and encoding caches empty, so each message is encoded and redacted as often as in a real
  run. Target 5 ms.
"""

from __future__ import annotations

import functools
import statistics
import sys
import tempfile
import time
from pathlib import Path
from typing import Any

import httpx
import numpy as np

from perf import (
    ROOT,
    Figure,
    median_seconds,
    paired_ratio,
    python_env,
    run_timed,
    run_with_cassette,
)
from pytest_emrd.cassette import (
    SUFFIX,
    cassette_path,
    clear_caches,
    decode,
    episode_cassette,
)
from pytest_emrd.trajectory import CONDITIONS, EpisodeSpec, Trajectory
from pytest_emrd.world._simulator import forget_views

CASSETTES = ROOT / "cassettes"
_SPAWNS = ("office", "conference", "kitchen", "entrance")


def _sample(episodes: tuple[int, ...]) -> tuple[EpisodeSpec, ...]:
    return tuple(
        EpisodeSpec("scout", condition, spawn, episode, modality="both")
        for episode in episodes
        for condition in CONDITIONS
        for spawn in _SPAWNS
    )


#: One committed episode per condition and spawn room (fixed, not picked by size).
SAMPLE = _sample((0,))
#: Two committed episodes per condition and spawn room.
SIZE_SAMPLE = _sample((0, 1))


class _Capture(httpx.BaseTransport):
    """A real HTTP transport (vcrpy patches it during a replay) keeping every exchange."""

    def __init__(self) -> None:
        self.inner = httpx.HTTPTransport()
        self.exchanges: list[tuple[httpx.Request, httpx.Response]] = []

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        request.read()
        response = self.inner.handle_request(request)
        self.exchanges.append((request, response))
        return response

    def close(self) -> None:
        self.inner.close()


def _protocol() -> str:
    from pytest_emrd.protocol import protocol_version

    return protocol_version()


@functools.cache
def _registry() -> Any:
    from pytest_emrd.agent import load_registry

    return load_registry()


def _scout_client(transport: httpx.BaseTransport | None = None) -> Any:
    """The scout model's client as a replay builds it (:func:`~pytest_emrd.episode.
    episode_client`), or on ``transport``."""
    from pytest_emrd.agent import OpenAICompatibleClient
    from pytest_emrd.episode import episode_client
    from pytest_emrd.reference import reference_base_url

    config = _registry().get("scout")
    if transport is None:
        return episode_client(config, live=False)
    return OpenAICompatibleClient(
        config, base_url=reference_base_url(), transport=transport, require_key=False
    )


def _replay(spec: EpisodeSpec, client: Any, *, as_sent_live: bool = False) -> Trajectory:
    """``spec`` replayed from its committed cassette with ``client``; errors are raised.

    ``as_sent_live``: frames travel as JPEG data URLs, as a live run sends them (what plain
    vcrpy records), instead of as the pixel digests a replay sends."""
    from pytest_emrd.episode import run_episode

    def run(s: EpisodeSpec, *, live: bool) -> Trajectory:
        replay = not (live or as_sent_live)
        return run_episode(s, registry=_registry(), client=client, replay=replay)

    done = run_with_cassette(
        spec, run, cassettes=CASSETTES, protocol=_protocol(), record_mode="none"
    )
    if done.trajectory.status == "errored":
        raise RuntimeError(f"replay of {spec.case_id} failed: {done.trajectory.error}")
    return done.trajectory


def _grid_seconds(repeat: int, warmup: int) -> tuple[float, float, float, float, float]:
    """Median wall and CPU times of the grid replayed into a fresh run directory, and of the
    same command run again on that finished directory (every episode read back from the
    store), bytecode cached; and of that second command with ``PYTHONDONTWRITEBYTECODE=1``:
    ``(fresh, fresh_cpu, again, again_cpu, again_nobytecode)``."""
    cached, uncached = python_env(bytecode=True), python_env(bytecode=False)
    runs: dict[str, list[tuple[float, float]]] = {"fresh": [], "again": [], "nobytecode": []}
    cmd = [sys.executable, "-m", "pytest", "benchmarks", "-n", "2", "-q", "-p", "no:cacheprovider"]
    cmd += ["--emrd-record-mode=none"]
    quick = ["--emrd-episodes=1"]  # the warm-up: every module of a replay and a resume
    for i in range(warmup + repeat):
        with tempfile.TemporaryDirectory() as tmp:
            for name, env in (("fresh", cached), ("again", cached), ("nobytecode", uncached)):
                args = [*cmd, f"--emrd-results={tmp}", *(quick if i < warmup else ())]
                done, wall, cpu = run_timed(args, cwd=ROOT, env=env)
                if done.returncode != 0 and i >= warmup:  # one episode a spawn may fail a gate
                    raise RuntimeError(f"replay of the grid failed:\n{done.stdout[-3000:]}")
                if i >= warmup:
                    runs[name].append((wall, cpu))
    median = statistics.median
    return (
        median(w for w, _ in runs["fresh"]),
        median(c for _, c in runs["fresh"]),
        median(w for w, _ in runs["again"]),
        median(c for _, c in runs["again"]),
        median(w for w, _ in runs["nobytecode"]),
    )


def _committed_sizes() -> tuple[float, float, int]:
    paths = sorted((CASSETTES / "scout").rglob(f"*{SUFFIX}"))
    if not paths:
        raise RuntimeError(f"no scout cassettes under {CASSETTES}; record them first")
    sizes = [p.stat().st_size / 1024 for p in paths]
    requests = [len(decode(p.read_bytes()).requests) for p in paths]
    slope, intercept = np.polyfit(requests, sizes, 1)
    return statistics.fmean(sizes), float(intercept + 50 * slope), len(paths)


def plain_vcrpy_yaml(exchanges: list[tuple[httpx.Request, httpx.Response]]) -> str:
    """What plain vcrpy writes for these exchanges: its YAML serialiser, bodies as sent."""
    from vcr.request import Request
    from vcr.serialize import serialize
    from vcr.serializers import yamlserializer

    requests = [Request(r.method, str(r.url), r.content, dict(r.headers)) for r, _ in exchanges]
    responses = [
        {
            "status": {"code": response.status_code, "message": response.reason_phrase},
            "headers": {k: response.headers.get_list(k) for k in response.headers},
            "body": {"string": response.content},
        }
        for _, response in exchanges
    ]
    return str(serialize({"requests": requests, "responses": responses}, yamlserializer))


def live_exchanges(
    spec: EpisodeSpec, *, as_sent_live: bool = True
) -> list[tuple[httpx.Request, httpx.Response]]:
    """The HTTP exchanges of ``spec`` as a live run sends them (JPEG frames), replayed from
    its committed cassette; or, with ``as_sent_live=False``, as a replay sends them (pixel
    digests)."""
    return _captured(spec, as_sent_live=as_sent_live)[1]


def _captured(
    spec: EpisodeSpec, *, as_sent_live: bool
) -> tuple[Trajectory, list[tuple[httpx.Request, httpx.Response]]]:
    """``spec`` replayed from its committed cassette, and the HTTP exchanges it made."""
    capture = _Capture()
    client = _scout_client(capture)
    try:
        trajectory = _replay(spec, client, as_sent_live=as_sent_live)
    finally:
        client.close()
    return trajectory, capture.exchanges


def _size_ratio(specs: tuple[EpisodeSpec, ...]) -> float:
    plain = 0
    ours = 0
    for spec in specs:
        plain += len(plain_vcrpy_yaml(live_exchanges(spec)).encode())
        ours += cassette_path(CASSETTES, spec).stat().st_size
    return plain / ours


def world_alone(trajectory: Trajectory) -> None:
    """What the episode loop asks of the world for ``trajectory``, and nothing else."""
    from pytest_emrd import world
    from pytest_emrd.episode import build_simulator, start_world, world_action

    spec = trajectory.spec
    sim = build_simulator(spec.backend)
    layout, _ = start_world(spec, sim)
    world.ground_truth(layout, sim.spawn_pose, spec.spawn)
    for step in trajectory.steps:
        sim.current_room()
        sim.visible_ids()
        sim.step(world_action(step.action, spec.variant)[0])
    sim.current_room()
    sim.close()


def _vs_world_ratio(specs: tuple[EpisodeSpec, ...], repeat: int, warmup: int) -> float:
    client = _scout_client()
    trajectories: list[Trajectory] = []

    def replay() -> None:
        clear_caches()
        forget_views()
        trajectories[:] = [_replay(spec, client) for spec in specs]

    def alone() -> None:
        forget_views()
        for trajectory in trajectories:
            world_alone(trajectory)

    try:
        return paired_ratio(replay, alone, repeat=repeat, warmup=warmup)
    finally:
        client.close()


def _httpx_vcrpy_floor_ratio(specs: tuple[EpisodeSpec, ...], repeat: int, warmup: int) -> float:
    """(world alone + httpx and vcrpy alone answering the same requests) / world alone: the
    least ``replay.vs_world_ratio`` a replay through httpx and vcrpy can reach.

    The requests are the sample's, as a replay sends them (digest frames), sent through a
    bare ``httpx.Client`` inside vcrpy's own ``use_cassette`` over its YAML files, with the
    cheapest matching vcrpy allows: the method alone, playback repeats on, so the first
    recorded interaction answers at once. Only the requests are timed: no cassette load, no
    redaction, no reply parsing, no agent; everything the replay does beyond this is ours."""
    import vcr

    captured = [_captured(spec, as_sent_live=False) for spec in specs]
    trajectories = [trajectory for trajectory, _ in captured]
    episodes = [exchanges for _, exchanges in captured]
    plain = httpx.Client()

    def alone() -> None:
        forget_views()
        for trajectory in trajectories:
            world_alone(trajectory)

    def requests(folder: Path) -> float:
        seconds = 0.0
        for n, exchanges in enumerate(episodes):
            path = str(folder / f"{n}.yaml")
            with vcr.use_cassette(
                path, record_mode="none", match_on=("method",), allow_playback_repeats=True
            ):
                start = time.process_time()
                for request, _ in exchanges:
                    plain.send(plain.build_request(**_resent(request))).read()
                seconds += time.process_time() - start
        return seconds

    with tempfile.TemporaryDirectory() as tmp:
        folder = Path(tmp)
        for n, exchanges in enumerate(episodes):
            (folder / f"{n}.yaml").write_text(plain_vcrpy_yaml(exchanges))
        try:
            for _ in range(warmup):  # both sides
                alone()
                requests(folder)
            ratios = []
            for _ in range(repeat):
                start = time.process_time()
                alone()
                world = time.process_time() - start
                ratios.append((world + requests(folder)) / world)
        finally:
            plain.close()
    return statistics.median(ratios)


def _resent(request: httpx.Request) -> dict[str, Any]:
    return {
        "method": request.method,
        "url": request.url,
        "content": request.content,
        "headers": request.headers,
    }


def _step_overhead_ms(repeat: int, warmup: int) -> float:
    from perf.loop import _Recorder

    spec = SAMPLE[0]
    client = _scout_client()
    recorder = _Recorder(client)
    _replay(spec, recorder)
    sent = recorder.sent

    def replay() -> None:
        clear_caches()  # as at the start of a run: nothing encoded or redacted yet
        with episode_cassette(
            cassette_path(CASSETTES, spec),
            protocol=_protocol(),
            record_mode="none",
            matching="strict",
            rerecord_command="(bench)",
        ):
            for messages in sent:
                client.complete(messages)

    try:
        seconds = median_seconds(replay, repeat=repeat, warmup=warmup)
    finally:
        client.close()
    return seconds / len(sent) * 1000


def run(*, repeat: int, warmup: int) -> list[Figure]:
    grid, grid_cpu, resume, resume_cpu, resume_nobytecode = _grid_seconds(repeat, warmup)
    overhead = _step_overhead_ms(repeat, warmup)
    vs_world = _vs_world_ratio(SAMPLE, repeat, warmup)
    floor = _httpx_vcrpy_floor_ratio(SAMPLE, repeat, warmup)
    ratio = _size_ratio(SIZE_SAMPLE)
    kb, kb_50, count = _committed_sizes()
    return [
        Figure("replay.grid_240_s", grid, "s", 20.0, repeat),
        Figure("replay.grid_240_cpu_s", grid_cpu, "s", None, repeat),
        Figure("replay.resume_240_s", resume, "s", 3.0, repeat),
        Figure("replay.resume_240_cpu_s", resume_cpu, "s", None, repeat),
        Figure("replay.resume_240_nobytecode_s", resume_nobytecode, "s", None, repeat),
        Figure("replay.vs_world_ratio", vs_world, "ratio", 1.2, repeat),
        Figure("replay.httpx_vcrpy_floor_vs_world_ratio", floor, "ratio", None, repeat),
        Figure("replay.cassette_kb_per_episode", kb, "KB", 15.0, count),
        Figure("replay.cassette_kb_per_50_steps", kb_50, "KB", 15.0, count),
        Figure(
            "replay.size_ratio_vs_plain_vcrpy",
            ratio,
            "ratio",
            500.0,
            len(SIZE_SAMPLE),
            higher_is_better=True,
        ),
        Figure("replay.step_overhead_ms", overhead, "ms", 5.0, repeat),
    ]
