"""A replay-only run that finds the cassettes an older release wrote says what to do."""

from __future__ import annotations

import shutil
from pathlib import Path

from pytest_emrd.cassette import Invocation, missing_summary
from pytest_emrd.trajectory import EpisodeSpec

LEGACY = Path(__file__).with_name("legacy")
#: ep00 was written in format 1 (gzip), ep01 in format 2 (xz).
SPECS = [EpisodeSpec("scout", "baseline", "office", n, modality="both") for n in (0, 1)]


def test_missing_cassettes_with_old_twins_are_named_and_recorded_again(tmp_path: Path) -> None:
    old = shutil.copytree(LEGACY, tmp_path / "cassettes")
    message = missing_summary(SPECS, total=3, root=old, invocation=Invocation())
    assert message is not None
    assert message.startswith(f"2 of 3 episode(s) have no cassette under {old}")
    assert "2 of them have a cassette an older pytest-emrd wrote (*.yaml.gz, *.yaml.xz)" in message
    assert "cannot replay with this release" in message
    assert "--emrd-record-mode=once" in message


def test_without_old_twins_the_message_does_not_mention_them(tmp_path: Path) -> None:
    message = missing_summary(SPECS, total=2, root=tmp_path, invocation=Invocation())
    assert message is not None and "older pytest-emrd" not in message
