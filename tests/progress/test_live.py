"""Live progress: steps and retries as they happen, in logs, the live line and the table."""

from __future__ import annotations

import logging
from pathlib import Path

import pytest

from pytest_emrd.agent import load_registry
from pytest_emrd.episode import Executor, protocol_version
from pytest_emrd.progress import (
    EpisodeWatch,
    LiveBoard,
    StatusFile,
    WorkerStatus,
    read_statuses,
    render_line,
)
from pytest_emrd.trajectory import EpisodeSpec

ROOT = Path(__file__).resolve().parents[2]


def _watched(executor: Executor, spec: EpisodeSpec, status: StatusFile | None = None):
    """The episode as the plugin runs it: through the executor, watched; and its retries."""
    tape = executor.tape(spec)
    with EpisodeWatch(spec, live=tape.live, status=status) as watch:
        episode = executor.run(tape, on_step=watch.on_step)
        watch.finish(episode.trajectory)
    return episode, watch.retries


def test_a_watched_live_episode_logs_steps_counts_retries_and_publishes(
    flaky, tmp_path, caplog, monkeypatch
):
    monkeypatch.setenv("PYTEST_XDIST_WORKER", "gw7")
    registry = load_registry(flaky.registry_file(tmp_path))
    spec = EpisodeSpec("flaky", "baseline", "office", 0, modality="both")
    executor = Executor(registry, cassettes=tmp_path / "cassettes", protocol=protocol_version())
    status = StatusFile(tmp_path / "run")
    with caplog.at_level(logging.INFO, logger="pytest_emrd"):
        episode, retries = _watched(executor, spec, status)
    executor.close()
    assert episode.recorded and episode.trajectory.status == "terminated"
    assert retries == 2
    messages = [r.getMessage() for r in caplog.records]
    steps = len(episode.trajectory.steps)
    assert "flaky-baseline-office-ep00 step 1/50: " in "\n".join(messages)
    assert any(m.startswith(f"flaky-baseline-office-ep00 step {steps}/50: Term(") for m in messages)
    retried = [r for r in caplog.records if r.levelno == logging.WARNING]
    said = [r.getMessage() for r in retried]
    assert [m.split(" attempt ")[1][:3] for m in said] == ["1/4", "2/4"], said
    assert "retrying in" in said[0] and "Cause: HTTP 503" in said[0]
    (published,) = read_statuses(tmp_path / "run")
    assert (published.worker, published.case, published.finished) == ("gw7", None, 1)
    assert (published.retries_total, published.errored) == (2, 0)


def test_a_replay_is_unchanged_and_logs_only_at_debug(flaky, tmp_path, caplog):
    """Watching changes nothing the model sees: the replay of a watched recording matches."""
    registry = load_registry(flaky.registry_file(tmp_path))
    spec = EpisodeSpec("flaky", "baseline", "kitchen", 1, modality="both")
    kwargs = {"cassettes": tmp_path / "cassettes", "protocol": protocol_version()}
    recorder = Executor(registry, record_mode="once", **kwargs)
    recorded, _ = _watched(recorder, spec)
    recorder.close()
    caplog.clear()
    replayer = Executor(registry, record_mode="none", **kwargs)
    with caplog.at_level(logging.INFO, logger="pytest_emrd"):
        replayed, _ = _watched(replayer, spec)
    replayer.close()
    assert replayed.trajectory == recorded.trajectory and not replayed.recorded
    assert caplog.records == [], "replays log steps at DEBUG only"


def _status(worker, **fields) -> WorkerStatus:
    base = dict(
        case=None,
        step=0,
        max_steps=50,
        retries=0,
        last_retry=None,
        finished=0,
        errored=0,
        retries_total=0,
    )
    return WorkerStatus(worker, **{**base, **fields})


def test_the_live_line_is_concise():
    line = render_line(
        [
            _status("gw0", case="gemini-baseline-office-ep03", step=12, finished=2),
            _status(
                "gw1",
                case="gemini-baseline-office-ep04",
                step=9,
                retries=2,
                finished=1,
                last_retry='HTTP 429: {"error": {"message": "Resource exhausted"}}',
                retries_total=1,
            ),
        ],
        total=96,
    )
    assert line == (
        "emrd live 3/96 recorded, 3 retries | gw0 gemini-baseline-office-ep03 step 12/50 | "
        "gw1 gemini-baseline-office-ep04 step 9/50, retry 2: "
        'HTTP 429: {"error": {"message": "Resource exhausted"}}'
    )


def test_the_board_prints_retries_at_once_and_steps_at_most_every_interval(tmp_path):
    now = [0.0]
    board = LiveBoard(tmp_path, total=4, interval=10.0, clock=lambda: now[0])
    status = StatusFile(tmp_path)
    assert board.poll() is None, "nothing published yet"
    status.update(case="scout-baseline-office-ep00", step=1, max_steps=50)
    assert board.poll().endswith("step 1/50")
    status.update(step=2)
    now[0] = 5.0
    assert board.poll() is None, "a step within the interval waits"
    status.update(retries=1, last_retry="retry 1/4 after HTTP 503")
    assert "retry 1: retry 1/4 after HTTP 503" in board.poll(), "a retry prints at once"
    now[0] = 16.0
    assert board.poll() is None, "nothing moved"
    status.update(step=3)
    assert board.poll().endswith("step 3/50, retry 1: retry 1/4 after HTTP 503")


@pytest.mark.slow
@pytest.mark.parametrize("xdist", [["-p", "no:xdist"], ["-n", "2"]], ids=["serial", "xdist"])
def test_a_live_session_shows_steps_retries_and_the_table(sandbox, flaky, xdist):
    flaky.fail_on = frozenset({2, 3})  # request 1 is the preflight probe
    sandbox.makepyfile(test_emrd=(ROOT / "benchmarks" / "test_emrd.py").read_text())
    models = flaky.registry_file(sandbox.path)
    result = sandbox.runpytest(
        "-p",
        "no:cacheprovider",
        "--emrd-model=flaky",
        f"--emrd-models={models}",
        "--emrd-condition=baseline",
        "--emrd-spawn=office",
        "--emrd-episodes=1",
        "--log-cli-level=INFO",
        *xdist,
    )
    result.assert_outcomes(passed=1)
    out = result.stdout.str()
    assert "emrd preflight flaky:" in out and "PASS  probe" in out
    table = result.stdout.lines[result.stdout.lines.index("tokens per model:") + 1 :]
    assert table[0].split()[-2:] == ["retries", "errored"]
    assert table[1].split()[0] == "flaky" and table[1].split()[-2:] == ["2", "0"]
    live = [line for line in result.stdout.lines if line.startswith("emrd live 0/1 recorded")]
    assert live[-1].startswith("emrd live 0/1 recorded, 2 retries | ")
    assert "flaky-baseline-office-ep00 step 0/50, retry 2: HTTP 503: " in live[-1]
    assert "vcr.cassette" not in out, "vcrpy's request bodies stay out of the live log"
    if xdist[0] == "-p":  # pytest shows live logs of its own process only
        assert "flaky-baseline-office-ep00 step 1/50: " in out
        assert "attempt 1/4 failed; retrying in" in out and "Cause: HTTP 503" in out
