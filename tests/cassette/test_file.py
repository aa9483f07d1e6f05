"""A cassette is a plain vcrpy cassette (JSON) inside xz, carrying a digest of its traffic."""

from __future__ import annotations

import gzip
import json
import lzma
import shutil
import subprocess
from pathlib import Path

import httpx
import pytest
import vcr
from vcr.serialize import deserialize
from vcr.serializers import jsonserializer

from pytest_emrd.cassette import EpisodePersister, cassette_path, decode, encode
from pytest_emrd.cli import main
from pytest_emrd.errors import CassetteError
from tests._episodes import run_with_cassette, traffic

from .conftest import PROTOCOL, FakeRunner, FakeServer


@pytest.fixture
def recorded(server: FakeServer, spec, tmp_path: Path) -> Path:
    run_with_cassette(
        spec, FakeRunner(server.url), cassettes=tmp_path, protocol=PROTOCOL, record_mode="once"
    )
    return cassette_path(tmp_path, spec)


def _replay(spec, server: FakeServer, root: Path):
    return run_with_cassette(
        spec, FakeRunner(server.url), cassettes=root, protocol=PROTOCOL, record_mode="none"
    )


def _rewrite(path: Path, edit) -> None:
    document = json.loads(lzma.decompress(path.read_bytes()))
    edit(document)
    path.write_bytes(lzma.compress(jsonserializer.serialize(document).encode()))


def test_decompressed_it_is_a_vcrpy_cassette_that_vcrpy_loads(recorded: Path) -> None:
    text = lzma.decompress(recorded.read_bytes()).decode()
    document = json.loads(text)
    assert sorted(document) == ["interactions", "metadata", "version"]
    assert document["version"] == 1 and len(document["interactions"]) == 4
    assert document["metadata"]["emrd"]["protocol"] == PROTOCOL
    requests, responses, metadata = deserialize(text, jsonserializer)
    assert [r.method for r in requests] == ["POST"] * 4
    assert b"pixels:" in requests[0].body and b"reply" in responses[0]["body"]["string"]
    assert metadata["emrd"]["digest"].startswith("sha256-file:")


def test_vcrpy_replays_it_through_the_persister(recorded: Path, server: FakeServer) -> None:
    """``vcr.use_cassette(path, persister=...)`` plays the recorded replies."""
    data = decode(recorded.read_bytes())
    persister = EpisodePersister(protocol=PROTOCOL, fresh=False, rerecord_command="x")
    my_vcr = vcr.VCR(record_mode="none", match_on=["method", "uri", "body"])
    my_vcr.register_persister(persister)
    request, live = data.requests[1], len(server.seen_headers)
    with my_vcr.use_cassette(str(recorded)), httpx.Client() as http:
        reply = http.post(request.uri, content=request.body).json()
    assert len(server.seen_headers) == live  # played from the file
    assert reply == json.loads(data.responses[1]["body"]["string"])


def test_decompressed_plain_vcrpy_replays_it(recorded: Path, tmp_path: Path) -> None:
    plain = tmp_path / "ep03.json"
    plain.write_bytes(lzma.decompress(recorded.read_bytes()))
    data = decode(recorded.read_bytes())
    request = data.requests[0]
    with (
        vcr.use_cassette(str(plain), serializer="json", record_mode="none"),
        httpx.Client() as http,
    ):
        reply = http.post(request.uri, content=request.body).json()
    assert reply == json.loads(data.responses[0]["body"]["string"])


def test_the_same_traffic_gives_the_same_file(server: FakeServer, spec, tmp_path: Path) -> None:
    """Byte for byte but for the latencies each recording measured."""
    for name in ("a", "b"):
        run_with_cassette(
            spec,
            FakeRunner(server.url),
            cassettes=tmp_path / name,
            protocol=PROTOCOL,
            record_mode="once",
        )
    a, b = (cassette_path(tmp_path / name, spec).read_bytes() for name in ("a", "b"))
    assert traffic(a) == traffic(b)
    assert encode(decode(a)) == a and encode(decode(b)) == b  # the bytes follow the content


def test_a_hand_edited_reply_is_refused_naming_the_rerecord_command(
    recorded: Path, server: FakeServer, spec, tmp_path: Path
) -> None:
    def edit(document: dict) -> None:
        body = document["interactions"][-1]["response"]["body"]
        body["string"] = body["string"].replace("reply", "REPLY")

    _rewrite(recorded, edit)
    with pytest.raises(CassetteError) as info:
        _replay(spec, server, tmp_path)
    message = str(info.value)
    assert "\n" not in message and "changed after it was recorded" in message
    assert "--emrd-record-mode=all" in message and str(recorded) in message


def test_an_edited_protocol_label_is_refused_too(
    recorded: Path, server: FakeServer, spec, tmp_path: Path
) -> None:
    def edit(document: dict) -> None:
        document["metadata"]["emrd"]["protocol"] = "test-protocol-0"

    _rewrite(recorded, edit)
    with pytest.raises(CassetteError, match="changed after it was recorded"):
        _replay(spec, server, tmp_path)


def test_a_gzip_cassette_replays(recorded: Path, server: FakeServer, spec, tmp_path: Path) -> None:
    recorded.write_bytes(gzip.compress(lzma.decompress(recorded.read_bytes()), mtime=0))
    assert _replay(spec, server, tmp_path).trajectory.status == "budget"


@pytest.mark.parametrize("old_name", ["ep00.yaml.gz", "ep01.yaml.xz"])
def test_a_cassette_of_an_older_release_is_refused_with_the_rerecord_command(
    old_name: str, server: FakeServer, spec, tmp_path: Path
) -> None:
    # Formats 1 (gzip) and 2 (xz) were written under protocols before this release's, so
    # their requests could never match today's: they are recorded again, not converted.
    legacy = Path(__file__).with_name("legacy") / "scout/baseline/default/office" / old_name
    target = cassette_path(tmp_path, spec)
    target.parent.mkdir(parents=True)
    shutil.copy(legacy, target)
    with pytest.raises(CassetteError) as info:
        _replay(spec, server, tmp_path)
    message = str(info.value)
    assert f"cassette={str(target)!r} was written by an older pytest-emrd" in message
    assert f"earlier protocol than {PROTOCOL}" in message
    assert "record it again: pytest" in message and "--emrd-record-mode=all" in message


def test_show_prints_what_xz_prints(recorded: Path, capsys: pytest.CaptureFixture[str]) -> None:
    assert main(["cassettes", "show", str(recorded)]) == 0
    shown = capsys.readouterr().out
    assert shown == lzma.decompress(recorded.read_bytes()).decode()
    if shutil.which("xz"):
        printed = subprocess.run(["xz", "-dc", str(recorded)], capture_output=True, check=True)
        assert printed.stdout.decode() == shown


def test_show_refuses_an_edited_cassette_in_one_line(
    recorded: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    _rewrite(recorded, lambda document: document["interactions"].pop())
    assert main(["cassettes", "show", str(recorded)]) == 2
    err = capsys.readouterr().err.strip()
    assert "\n" not in err and "do not match the digest" in err


def test_a_cassette_whose_digest_covers_its_interactions_only_is_refused(
    recorded: Path, server: FakeServer, spec, tmp_path: Path
) -> None:
    """Written before the digest covered the whole file (``sha256:``): recorded again."""
    _rewrite(recorded, lambda d: d["metadata"]["emrd"].update(digest="sha256:" + "0" * 64))
    with pytest.raises(CassetteError) as info:
        _replay(spec, server, tmp_path)
    assert "its digest covers its interactions only" in str(info.value)
    assert "--emrd-record-mode=all" in str(info.value)


def test_an_edited_metadata_field_is_refused(
    recorded: Path, server: FakeServer, spec, tmp_path: Path
) -> None:
    """The digest covers the whole file: ``metadata.emrd.raw`` too."""
    document = json.loads(lzma.decompress(recorded.read_bytes()))
    document["metadata"]["emrd"]["raw"] = [0]
    text = jsonserializer.serialize(document)
    recorded.write_bytes(lzma.compress(text.encode()))
    with pytest.raises(CassetteError, match="changed after it was recorded"):
        _replay(spec, server, tmp_path)
