"""The results store: atomic, computed once across concurrent askers, resumable; metrics
measured once and kept for the same episode file."""

from __future__ import annotations

import threading
import time
from typing import Any

import pytest

from pytest_emrd.cassette import EpisodeRun
from pytest_emrd.metrics import episode_metrics
from pytest_emrd.run import ResultsStore, episode_path, load_run_dirs, scratch_dir
from pytest_emrd.trajectory import EpisodeSpec, Trajectory

from .conftest import make_trajectory

SPEC = EpisodeSpec("scout", "baseline", "office", 0)


class Counter:
    def __init__(self, status: str = "budget", protocol: str = "p1") -> None:
        self.calls = 0
        self.status, self.protocol = status, protocol

    def __call__(self, spec: EpisodeSpec) -> EpisodeRun:
        self.calls += 1
        time.sleep(0.05)
        return EpisodeRun(
            make_trajectory(spec, status=self.status, protocol=self.protocol), True, 0, 0.05
        )


def test_concurrent_askers_compute_an_episode_once(tmp_path):
    compute = Counter()
    results = []

    def ask() -> None:
        store = ResultsStore(tmp_path, session="s1", protocol="p1")
        results.append(store.get_or_compute(SPEC, compute))

    threads = [threading.Thread(target=ask) for _ in range(4)]
    for t in threads:
        t.start()
    for t in threads:
        t.join()
    assert compute.calls == 1
    assert sum(r.computed_now for r in results) == 1
    assert len({r.trajectory for r in results}) == 1
    assert [p.name for p in (tmp_path / "episodes").iterdir()] == [
        "scout-baseline-office-ep00.json"
    ]


def test_resume_reuses_finished_episodes_of_the_same_protocol(tmp_path):
    ResultsStore(tmp_path, session="s1", protocol="p1").get_or_compute(SPEC, Counter())
    again = Counter()
    stored = ResultsStore(tmp_path, session="s2", protocol="p1").get_or_compute(SPEC, again)
    assert again.calls == 0 and stored.head.session == "s1" and not stored.computed_now


def test_resume_recomputes_stale_protocol_and_errored_episodes(tmp_path):
    ResultsStore(tmp_path, session="s1", protocol="p0").get_or_compute(SPEC, Counter(protocol="p0"))
    fresh = Counter(status="errored")
    ResultsStore(tmp_path, session="s2", protocol="p1").get_or_compute(SPEC, fresh)
    assert fresh.calls == 1
    same_session = Counter()
    ResultsStore(tmp_path, session="s2", protocol="p1").get_or_compute(SPEC, same_session)
    assert same_session.calls == 0  # within the session an errored episode is final
    next_session = Counter()
    ResultsStore(tmp_path, session="s3", protocol="p1").get_or_compute(SPEC, next_session)
    assert next_session.calls == 1  # a rerun retries it


def test_unreadable_leftovers_are_recomputed(tmp_path):
    store = ResultsStore(tmp_path, session="s1", protocol="p1")
    episode_path(tmp_path, SPEC).parent.mkdir(parents=True)
    episode_path(tmp_path, SPEC).write_text("{half a file")
    compute = Counter()
    store.get_or_compute(SPEC, compute)
    assert compute.calls == 1 and [t.spec for t in load_run_dirs([tmp_path])] == [SPEC]


def test_several_run_dirs_merge_by_case(tmp_path):
    other = EpisodeSpec("scout", "baseline", "kitchen", 1)
    ResultsStore(tmp_path / "a", session="s", protocol="p1").get_or_compute(SPEC, Counter())
    ResultsStore(tmp_path / "b", session="s", protocol="p1").get_or_compute(other, Counter())
    ResultsStore(tmp_path / "b", session="s", protocol="p1").get_or_compute(SPEC, Counter())
    merged = load_run_dirs([tmp_path / "a", tmp_path / "b"])
    assert [t.spec for t in merged] == [other, SPEC]


@pytest.fixture
def measured(monkeypatch) -> list[Trajectory]:
    """The trajectories ``episode_metrics`` measures from now on."""
    import pytest_emrd.metrics as metrics

    seen: list[Trajectory] = []
    real = metrics.episode_metrics

    def counted(trajectory: Trajectory) -> Any:
        seen.append(trajectory)
        return real(trajectory)

    monkeypatch.setattr(metrics, "episode_metrics", counted)
    return seen


def test_metrics_are_measured_once_and_read_back_by_later_processes(tmp_path, measured):
    first = ResultsStore(tmp_path, session="s1", protocol="p1")
    stored = first.get_or_compute(SPEC, Counter(), measure=True)
    assert measured == [stored.trajectory]  # the one in memory, under the episode's lock
    again = ResultsStore(tmp_path, session="s2", protocol="p1")
    reused = again.get_or_compute(SPEC, Counter(), measure=True)
    assert again.metrics([reused]) == [episode_metrics(stored.trajectory)]
    assert len(measured) == 1


def test_metrics_of_a_rewritten_episode_are_measured_again(tmp_path, measured):
    store = ResultsStore(tmp_path, session="s1", protocol="p1")
    store.metrics([store.get_or_compute(SPEC, Counter(status="errored"))])
    rerun = ResultsStore(tmp_path, session="s2", protocol="p1")  # retries the errored one
    (fresh,) = rerun.metrics([rerun.get_or_compute(SPEC, Counter())])
    assert [t.status for t in measured] == ["errored", "budget"] and not fresh.errored
    assert len(list((scratch_dir(tmp_path) / "metrics").iterdir())) == 1  # the stale one gone
