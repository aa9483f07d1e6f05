"""Per-episode metrics saved beside the results store: measured once per stored episode."""

from __future__ import annotations

from dataclasses import asdict, dataclass
from typing import Any

import pytest

from pytest_emrd.cassette import EpisodeRun
from pytest_emrd.metrics import EpisodeMetrics, episode_metrics
from pytest_emrd.run import (
    EPISODE_METRICS_CODE,
    EPISODE_METRICS_LIBRARIES,
    MeasuredStore,
    ResultsStore,
    StoredEpisode,
    code_fingerprint,
    measured_episodes,
)
from pytest_emrd.trajectory import EpisodeSpec, Trajectory

from .conftest import make_trajectory

SPEC = EpisodeSpec("scout", "baseline", "office", 0)


@dataclass(frozen=True)
class Steps:
    spec: EpisodeSpec
    errored: bool
    steps: int

    def to_dict(self) -> dict[str, Any]:
        return {"spec": asdict(self.spec), "errored": self.errored, "steps": self.steps}

    @classmethod
    def from_dict(cls, data: dict[str, Any]) -> Steps:
        return cls(EpisodeSpec(**data["spec"]), data["errored"], data["steps"])


class Measure:
    def __init__(self) -> None:
        self.calls = 0

    def __call__(self, trajectory: Trajectory) -> Steps:
        self.calls += 1
        return Steps(trajectory.spec, trajectory.status == "errored", len(trajectory.steps))


def _store(tmp_path, *, session: str = "s1", protocol: str = "p1") -> ResultsStore:
    return ResultsStore(tmp_path, session=session, protocol=protocol)


def _episode(store: ResultsStore, status: str = "budget"):
    def episode(spec: EpisodeSpec) -> StoredEpisode:
        trajectory = make_trajectory(spec, status=status, protocol=store.protocol)
        return store.get_or_compute(spec, lambda s: EpisodeRun(trajectory, False, 0, 0.0))

    return episode


def _measured(store: ResultsStore, measure: Measure, code: str = "c1") -> MeasuredStore[Steps]:
    return MeasuredStore(store, measure=measure, load=Steps.from_dict, code=code)


def _no_episode(spec: EpisodeSpec) -> StoredEpisode:
    raise AssertionError(f"{spec.case_id} was read or computed although its metrics are saved")


def test_metrics_are_measured_once_and_read_back_by_another_process(tmp_path):
    store, measure = _store(tmp_path), Measure()
    first = _measured(store, measure).get(SPEC, _episode(store))
    again = _measured(_store(tmp_path, session="s2"), measure).get(SPEC, _no_episode)
    assert again == first == Steps(SPEC, False, 0)
    assert measure.calls == 1
    assert (tmp_path / "metrics" / f"{SPEC.case_id}.json").is_file()


def test_a_recomputed_episode_or_changed_code_is_measured_again(tmp_path):
    store, measure = _store(tmp_path), Measure()
    _measured(store, measure).get(SPEC, _episode(store))
    _measured(store, measure, code="c2").get(SPEC, _episode(store))
    assert measure.calls == 2
    path = store.path_for(SPEC)
    path.write_bytes(path.read_bytes().replace(b'"seconds":0.0', b'"seconds":1.0'))
    _measured(store, measure, code="c2").get(SPEC, _episode(store))
    assert measure.calls == 3


def test_another_protocol_is_not_read_back(tmp_path):
    old, measure = _store(tmp_path, protocol="p0"), Measure()
    _measured(old, measure).get(SPEC, _episode(old))
    new = _store(tmp_path, protocol="p1")
    assert _measured(new, measure).get(SPEC, _episode(new)) == Steps(SPEC, False, 0)
    assert measure.calls == 2
    assert new.get_or_compute(SPEC, _no_episode).trajectory.protocol == "p1"


def test_errored_episodes_are_not_saved(tmp_path):
    store, measure = _store(tmp_path), Measure()
    assert _measured(store, measure).get(SPEC, _episode(store, "errored")).errored
    assert not (tmp_path / "metrics").exists()


def test_unreadable_saved_metrics_are_measured_again(tmp_path):
    store, measure = _store(tmp_path), Measure()
    measured = _measured(store, measure)
    measured.get(SPEC, _episode(store))
    measured.path_for(SPEC).write_text("{not json")
    assert measured.get(SPEC, _episode(store)) == Steps(SPEC, False, 0)
    assert measure.calls == 2


def test_saved_episode_metrics_round_trip_exactly(tmp_path):
    store = _store(tmp_path)
    code = code_fingerprint(EPISODE_METRICS_CODE, EPISODE_METRICS_LIBRARIES)
    measured = MeasuredStore(
        store, measure=episode_metrics, load=EpisodeMetrics.from_dict, code=code
    )
    first = measured.get(SPEC, _episode(store))
    assert measured.get(SPEC, _no_episode) == first == episode_metrics(make_trajectory(SPEC))


def test_code_fingerprint_follows_the_source_and_library_versions(tmp_path, monkeypatch):
    package = tmp_path / "emrd_fp_probe"
    package.mkdir()
    (package / "__init__.py").write_text("")
    (package / "_a.py").write_text("X = 1\n")
    monkeypatch.syspath_prepend(str(tmp_path))
    before = code_fingerprint(["emrd_fp_probe"])
    assert code_fingerprint(["emrd_fp_probe"]) == before
    (package / "_a.py").write_text("X = 2\n")
    assert code_fingerprint(["emrd_fp_probe"]) != before
    assert code_fingerprint(["emrd_fp_probe"], ["numpy"]) != code_fingerprint(["emrd_fp_probe"])
    with pytest.raises(ModuleNotFoundError, match="emrd_fp_missing"):
        code_fingerprint(["emrd_fp_missing"])


def test_reading_runs_uses_what_each_run_saved_and_measures_the_rest(tmp_path):
    first, second, measure = tmp_path / "a", tmp_path / "b", Measure()
    store_a, store_b = _store(first), _store(second)
    _measured(store_a, measure).get(SPEC, _episode(store_a))  # run a saved its metrics
    other = EpisodeSpec("scout", "baseline", "kitchen", 0)
    _episode(store_b)(other)  # run b stored an episode but saved no metrics
    trajectories = [store_a.get_or_compute(SPEC, _no_episode).trajectory,
                    store_b.get_or_compute(other, _no_episode).trajectory]  # fmt: skip
    again = Measure()
    got = measured_episodes([first, second], trajectories, measure=again, load=Steps.from_dict,
                            code="c1")  # fmt: skip
    assert got == [Steps(SPEC, False, 0), Steps(other, False, 0)]
    assert again.calls == 1  # only the episode without saved metrics
    assert not (second / "metrics").exists()  # reading a run never writes to it
    stale = measured_episodes([first], trajectories[:1], measure=again, load=Steps.from_dict,
                              code="c2")  # fmt: skip
    assert stale == [Steps(SPEC, False, 0)] and again.calls == 2  # other code: measured again
