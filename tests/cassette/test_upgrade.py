"""``emrd cassettes upgrade`` converts the cassettes older releases wrote, once, verified."""

from __future__ import annotations

import shutil
from pathlib import Path

import pytest

from pytest_emrd.agent import load_registry
from pytest_emrd.cassette import (
    Invocation,
    cassette_path,
    decode,
    missing_summary,
    run_with_cassette,
)
from pytest_emrd.cli import main
from pytest_emrd.episode import agent_runner, protocol_version
from pytest_emrd.errors import EmrdError
from pytest_emrd.trajectory import EpisodeSpec

LEGACY = Path(__file__).with_name("legacy")
#: The protocol the legacy cassettes were recorded under.
LEGACY_PROTOCOL = "builtin-4+p2"
#: ep00 was written in format 1 (gzip), ep01 in format 2 (xz, shipped system prompt named).
SPECS = [EpisodeSpec("scout", "baseline", "office", n, modality="both") for n in (0, 1)]


@pytest.fixture
def old(tmp_path: Path) -> Path:
    return shutil.copytree(LEGACY, tmp_path / "cassettes")


def test_both_old_formats_become_vcrpy_cassettes_that_replay(
    old: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    assert main(["cassettes", "upgrade", str(old)]) == 0
    assert "upgraded 2 cassettes" in capsys.readouterr().out
    folder = old / "scout/baseline/default/office"
    assert sorted(p.name for p in folder.iterdir()) == ["ep00.json.xz", "ep01.json.xz"]
    runner = agent_runner(load_registry())
    try:
        for spec in SPECS:
            upgraded = decode(cassette_path(old, spec).read_bytes())
            # The protocol they were recorded under travels with them; today's world refuses
            # them as stale, with the command that records them again.
            assert upgraded.protocol == LEGACY_PROTOCOL and upgraded.requests
            with pytest.raises(EmrdError, match=r"(?s)builtin-4\+p2.*--emrd-record-mode=all"):
                run_with_cassette(
                    spec, runner, cassettes=old, protocol=protocol_version(), record_mode="none"
                )
    finally:
        runner.close()


def test_a_second_upgrade_has_nothing_to_do(old: Path, capsys) -> None:
    main(["cassettes", "upgrade", str(old)])
    converted = {p: p.read_bytes() for p in old.rglob("*.json.xz")}
    assert main(["cassettes", "upgrade", str(old)]) == 0
    assert "nothing to upgrade" in capsys.readouterr().out
    assert {p: p.read_bytes() for p in old.rglob("*.json.xz")} == converted


def test_an_existing_new_twin_is_left_to_the_user(old: Path, capsys) -> None:
    folder = old / "scout/baseline/default/office"
    (folder / "ep00.json.xz").write_bytes(b"mine")
    assert main(["cassettes", "upgrade", str(old)]) == 2
    assert "has a twin ep00.json.xz" in capsys.readouterr().err
    assert (folder / "ep00.yaml.gz").is_file() and (folder / "ep00.json.xz").read_bytes() == b"mine"


def test_a_file_that_is_no_cassette_is_named(old: Path, capsys) -> None:
    bad = old / "scout/baseline/default/office/ep02.yaml.xz"
    bad.write_bytes(b"\xfd7zXZ\x00 garbage")
    assert main(["cassettes", "upgrade", str(old)]) == 2
    assert f"cassette={str(bad)!r} is not an old cassette" in capsys.readouterr().err


def test_a_replay_only_run_missing_old_cassettes_says_to_convert_them(old: Path) -> None:
    message = missing_summary(SPECS, total=2, root=old, invocation=Invocation())
    assert "2 of them have a cassette an older pytest-emrd wrote" in message
    assert f"emrd cassettes upgrade {old}." in message
