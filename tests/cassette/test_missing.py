"""A replay asking for more episodes than were recorded names the recorded count and the
setting to change (a shard's command asks for the run's count, not its own highest + 1)."""

from __future__ import annotations

from pathlib import Path

from pytest_emrd.cassette import Invocation, cassette_path, missing_summary
from pytest_emrd.trajectory import EpisodeSpec


def _specs(episodes: range) -> list[EpisodeSpec]:
    return [EpisodeSpec("my-vlm", "baseline", "office", n, modality="both") for n in episodes]


def test_more_episodes_than_recorded_names_the_count_and_the_setting(tmp_path: Path) -> None:
    for spec in _specs(range(2)):
        path = cassette_path(tmp_path, spec)
        path.parent.mkdir(parents=True, exist_ok=True)
        path.write_bytes(b"")
    shard = _specs(range(2, 17))  # shard 1/4 of 20 asked: its highest is ep16
    message = missing_summary(shard, total=17, root=tmp_path, invocation=Invocation(), episodes=20)
    assert message is not None
    assert "asks for 20 episode(s) per spawn room" in message
    assert "EMRD_EPISODES" in message and "the cassettes hold 2" in message
    assert "set --emrd-episodes=2" in message
    assert "--emrd-episodes=20" in message and "--emrd-episodes=17" not in message


def test_a_gap_in_the_recording_is_not_called_a_count(tmp_path: Path) -> None:
    path = cassette_path(tmp_path, _specs(range(3))[2])
    path.parent.mkdir(parents=True)
    path.write_bytes(b"")
    message = missing_summary(
        _specs(range(2)), total=3, root=tmp_path, invocation=Invocation(), episodes=3
    )
    assert message is not None and "set --emrd-episodes" not in message
