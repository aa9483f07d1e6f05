"""Format-1 cassettes (``.yaml.gz``) replay as they are and upgrade to ``.yaml.xz`` verified."""

from __future__ import annotations

import lzma
import shutil
from pathlib import Path

import pytest

from pytest_emrd.cassette import (
    EpisodePersister,
    cassette_path,
    decode,
    same_traffic,
    upgrade,
)
from pytest_emrd.cli import main
from pytest_emrd.errors import CassetteError
from pytest_emrd.trajectory import EpisodeSpec

ROOT = Path(__file__).resolve().parents[2] / "cassettes"
FORMAT1 = Path(__file__).with_name("format1")
SPEC = EpisodeSpec("scout", "baseline", "office", 0, modality="both")


@pytest.fixture
def old_tree(tmp_path: Path) -> Path:
    return Path(shutil.copytree(FORMAT1, tmp_path / "cassettes"))


def test_saving_over_a_format_1_cassette_writes_the_xz_file_in_its_place(old_tree: Path):
    old = cassette_path(old_tree, SPEC)
    data = decode(old.read_bytes())
    persister = EpisodePersister(protocol=data.protocol, fresh=False, rerecord_command="x")
    persister.save_cassette(old, {"requests": data.requests, "responses": data.responses})
    assert not old.exists() and cassette_path(old_tree, SPEC) == old.with_name("ep00.yaml.xz")
    assert same_traffic(decode(cassette_path(old_tree, SPEC).read_bytes()), data)


def test_upgrade_rewrites_every_old_file_as_the_committed_one(old_tree: Path):
    done = list(upgrade(old_tree))
    assert len(done) == 3 and all(d.new_bytes < d.old_bytes for d in done)
    assert not list(old_tree.rglob("*.yaml.gz"))
    for item in done:
        committed = ROOT / item.new.relative_to(old_tree)
        assert item.new.read_bytes() == committed.read_bytes()
    assert list(upgrade(old_tree)) == []


def test_upgrade_stops_at_an_unreadable_file_or_a_twin(old_tree: Path):
    twin = cassette_path(old_tree, SPEC).with_name("ep00.yaml.xz")
    shutil.copy(ROOT / twin.relative_to(old_tree), twin)
    with pytest.raises(CassetteError, match=r"twin ep00\.yaml\.xz already"):
        list(upgrade(old_tree))
    twin.unlink()
    cassette_path(old_tree, SPEC).write_bytes(b"\x1f\x8b garbage")
    with pytest.raises(CassetteError, match=r"ep00\.yaml\.gz.*not readable"):
        list(upgrade(old_tree))


def test_the_upgrade_command(old_tree: Path, capsys: pytest.CaptureFixture[str]):
    assert main(["cassettes", "upgrade", str(old_tree)]) == 0
    assert "upgraded 3 cassettes under" in capsys.readouterr().out
    assert main(["cassettes", "upgrade", str(old_tree)]) == 0
    assert "nothing to upgrade" in capsys.readouterr().out
    assert main(["cassettes", "upgrade", str(old_tree / "nowhere")]) == 2
    assert "is not a folder" in capsys.readouterr().err


def test_a_cassette_of_a_newer_release_asks_for_an_upgrade(tmp_path: Path):
    path = tmp_path / "ep00.yaml.xz"
    path.write_bytes(lzma.compress(b"format: emrd-cassette/9\n", format=lzma.FORMAT_XZ))
    persister = EpisodePersister(protocol="p", fresh=False, rerecord_command="pytest again")
    with pytest.raises(CassetteError, match=r"newer pytest-emrd.*pip install -U.*pytest again"):
        persister.load_cassette(path)
