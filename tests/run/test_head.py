"""Episode files carry their own head: a resumed run reuses an episode from the file's first
line without decoding its trajectory, and a run directory holds nothing but ``run.json`` and
one file per episode."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pytest_emrd.cassette import EpisodeRun
from pytest_emrd.errors import ProtocolError
from pytest_emrd.run import (
    EpisodeHead,
    ResultsStore,
    RunIdentity,
    StoredEpisode,
    episode_path,
    load_run_episodes,
    read_episode,
)
from pytest_emrd.trajectory import EpisodeSpec, Usage

from .conftest import make_trajectory

SPEC = EpisodeSpec("scout", "baseline", "office", 0)
IDENTITY = RunIdentity(grid={"models": ["scout"]}, shard=None)


def _never(spec: EpisodeSpec) -> EpisodeRun:
    raise AssertionError(f"{spec.case_id} was computed again")


def _decoded(stored: StoredEpisode) -> bool:
    """Whether the trajectory was decoded (or only the head read)."""
    return "trajectory" in stored.__dict__


def _store(run_dir: Path, session: str = "s1") -> ResultsStore:
    return ResultsStore(run_dir, session=session, protocol="p1", identity=IDENTITY)


def _computed(run_dir: Path) -> StoredEpisode:
    run = EpisodeRun(make_trajectory(SPEC), True, 2, 0.25)
    return _store(run_dir).get_or_compute(SPEC, lambda spec: run)


def test_a_run_directory_holds_run_json_and_one_file_per_episode(tmp_path):
    _computed(tmp_path)
    files = sorted(str(p.relative_to(tmp_path)) for p in tmp_path.rglob("*"))
    assert files == ["episodes", f"episodes/{SPEC.case_id}.json", "run.json"]


def test_an_episode_file_is_one_json_document_whose_first_line_is_its_head(tmp_path):
    computed = _computed(tmp_path)
    blob = episode_path(tmp_path, SPEC).read_bytes()
    document = json.loads(blob)
    assert document["store_schema"] == 2
    assert EpisodeHead.from_dict(document["head"]) == computed.head
    assert document["trajectory"] == computed.trajectory.to_dict()
    first, second = blob.splitlines()
    assert json.loads(first[:-1] + b"}")["head"] == document["head"]
    assert second.startswith(b'"trajectory":')


def test_a_resume_reads_the_head_and_decodes_the_trajectory_on_first_use(tmp_path):
    computed = _computed(tmp_path)
    resumed = _store(tmp_path, "s2").get_or_compute(SPEC, _never)
    assert not _decoded(resumed)
    assert (
        resumed.head
        == computed.head
        == EpisodeHead(
            spec=SPEC,
            protocol="p1",
            status="budget",
            steps=0,
            chosen_room=None,
            final_map_entries=0,
            usage=Usage(),
            error=None,
            session="s1",
            recorded=True,
            frame_drift=2,
            seconds=0.25,
            retries=0,
        )
    )
    assert resumed.trajectory == computed.trajectory and _decoded(resumed)


def test_an_episode_file_replaced_after_its_head_was_read_is_refused(tmp_path):
    _computed(tmp_path)
    resumed = _store(tmp_path, "s2").get_or_compute(SPEC, _never)
    path = episode_path(tmp_path, SPEC)
    path.write_bytes(path.read_bytes().replace(b'"seconds":0.25', b'"seconds":0.26'))
    with pytest.raises(ProtocolError, match="changed while this run was reading it"):
        _ = resumed.trajectory


def test_a_head_that_does_not_describe_its_trajectory_is_refused(tmp_path):
    _computed(tmp_path)
    path = episode_path(tmp_path, SPEC)
    path.write_bytes(path.read_bytes().replace(b'"status":"budget"', b'"status":"terminated"', 1))
    stored = read_episode(path)
    assert stored.head.status == "terminated"
    with pytest.raises(ProtocolError, match=r"cannot be read.*does not describe its trajectory"):
        _ = stored.trajectory


def test_a_trajectory_of_an_unknown_schema_is_recomputed(tmp_path):
    _computed(tmp_path)
    path = episode_path(tmp_path, SPEC)
    blob = path.read_bytes().replace(b'"trajectory_schema":2', b'"trajectory_schema":99')
    path.write_bytes(blob.replace(b'"schema_version":2}}', b'"schema_version":99}}'))
    assert _store(tmp_path, "s2").reusable(SPEC) is None
    with pytest.raises(ProtocolError, match="schema_version=99"):
        read_episode(path)


def test_an_old_layout_run_directory_is_read_and_resumed_ignoring_its_other_folders(tmp_path):
    trajectory = make_trajectory(SPEC)
    legacy = {"store_schema": 1, "session": "old", "recorded": False, "frame_drift": 0,
              "seconds": 1.5, "trajectory": trajectory.to_dict()}  # fmt: skip
    path = tmp_path / "episodes" / f"{SPEC.case_id}.json"
    path.parent.mkdir()
    path.write_text(json.dumps(legacy, separators=(",", ":")))
    for folder in ("heads", "metrics", "locks", "aggregates"):
        (tmp_path / folder).mkdir()
        (tmp_path / folder / "leftover.json").write_text("{}")
    (stored,) = load_run_episodes([tmp_path])
    assert stored.trajectory == trajectory
    assert stored.head.session == "old" and stored.head.seconds == 1.5
    resumed = _store(tmp_path, "s2").get_or_compute(SPEC, _never)
    assert resumed.head == stored.head
    assert json.loads(path.read_bytes())["store_schema"] == 1  # reading never rewrites it


def test_a_stored_episode_round_trips_through_its_file():
    stored = StoredEpisode.of(
        make_trajectory(SPEC, status="errored"),
        session="s",
        recorded=False,
        frame_drift=0,
        seconds=1.0,
    )
    again = StoredEpisode.from_json(stored.to_json())
    assert again.head == stored.head and again.trajectory == stored.trajectory


def test_an_episode_file_of_an_unknown_layout_is_one_line_naming_it(tmp_path):
    _computed(tmp_path)
    path = episode_path(tmp_path, SPEC)
    path.write_bytes(path.read_bytes().replace(b'"store_schema":2', b'"store_schema":3'))
    message = r"file=.*read \(store_schema=3 is not one pytest-emrd .* reads \(1 or 2\)\); delete"
    with pytest.raises(ProtocolError, match=message):
        load_run_episodes([tmp_path])
    assert _store(tmp_path, "s2").reusable(SPEC) is None  # recomputed by a resume


def test_decoding_a_trajectory_without_keeping_it_gives_the_same_trajectory(tmp_path):
    computed = _computed(tmp_path)
    resumed = _store(tmp_path, "s2").get_or_compute(SPEC, _never)
    assert resumed.decode_trajectory() == computed.trajectory and not _decoded(resumed)
    assert resumed.trajectory is resumed.decode_trajectory()  # once kept, the kept one
