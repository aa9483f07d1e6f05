"""Episode heads: a resumed run reuses an episode without decoding its trajectory, and only
while the head describes the very file stored now."""

from __future__ import annotations

import json

import pytest

from pytest_emrd.cassette import EpisodeRun
from pytest_emrd.errors import ProtocolError
from pytest_emrd.run import EpisodeHead, ResultsStore, StoredEpisode
from pytest_emrd.run._head import head_path
from pytest_emrd.trajectory import EpisodeSpec, Trajectory, Usage

from .conftest import make_trajectory

SPEC = EpisodeSpec("scout", "baseline", "office", 0)


def _never(spec: EpisodeSpec) -> EpisodeRun:
    raise AssertionError(f"{spec.case_id} was computed again")


def _decoded(stored: StoredEpisode) -> bool:
    """Whether the store decoded the episode file (or only read its head)."""
    return isinstance(stored.source, Trajectory)


def _store(tmp_path, session="s1"):
    return ResultsStore(tmp_path, session=session, protocol="p1")


def _computed(tmp_path):
    run = EpisodeRun(make_trajectory(SPEC), True, 2, 0.25)
    return _store(tmp_path).get_or_compute(SPEC, lambda spec: run)


def test_a_computed_episode_writes_its_head_and_a_resume_reads_the_trajectory_lazily(tmp_path):
    computed = _computed(tmp_path)
    assert head_path(tmp_path, SPEC).is_file()
    resumed = _store(tmp_path, "s2").get_or_compute(SPEC, _never)
    assert not _decoded(resumed)
    assert resumed.head == computed.head
    assert (resumed.session, resumed.recorded, resumed.frame_drift) == ("s1", True, 2)
    assert resumed.head == EpisodeHead(
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
    assert resumed.trajectory == computed.trajectory


def test_a_changed_episode_file_is_read_in_full_and_its_head_rewritten(tmp_path):
    _computed(tmp_path)
    path = _store(tmp_path).path_for(SPEC)
    document = json.loads(path.read_bytes())
    document["seconds"] = 9.5
    path.write_text(json.dumps(document))
    resumed = _store(tmp_path, "s2").get_or_compute(SPEC, _never)
    assert resumed.seconds == 9.5 and _decoded(resumed)
    assert _store(tmp_path, "s3").get_or_compute(SPEC, _never).seconds == 9.5


@pytest.mark.parametrize("field", ["code", "episode_sha256"])
def test_a_head_written_for_other_code_or_bytes_is_not_used(tmp_path, field):
    _computed(tmp_path)
    path = head_path(tmp_path, SPEC)
    document = json.loads(path.read_bytes())
    document[field] = "0" * 64
    document["head"]["seconds"] = 123.0  # a stale head's claims must not be believed
    path.write_text(json.dumps(document))
    resumed = _store(tmp_path, "s2").get_or_compute(SPEC, _never)
    assert resumed.seconds == 0.25
    assert json.loads(path.read_bytes())[field] != "0" * 64  # rewritten


def test_a_run_dir_without_heads_is_read_in_full_once(tmp_path):
    _computed(tmp_path)
    head_path(tmp_path, SPEC).unlink()
    first = _store(tmp_path, "s2").get_or_compute(SPEC, _never)
    assert _decoded(first) and head_path(tmp_path, SPEC).is_file()
    second = _store(tmp_path, "s3").get_or_compute(SPEC, _never)
    assert not _decoded(second) and second.head == first.head


def test_an_episode_file_changed_after_its_head_was_read_is_refused(tmp_path):
    _computed(tmp_path)
    resumed = _store(tmp_path, "s2").get_or_compute(SPEC, _never)
    path = _store(tmp_path).path_for(SPEC)
    path.write_bytes(path.read_bytes().replace(b'"seconds":0.25', b'"seconds":0.26'))
    with pytest.raises(ProtocolError, match="changed while this run was reading it"):
        _ = resumed.trajectory


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
