"""The content-addressed cassette format round-trips exactly and rejects what it is not."""

from __future__ import annotations

import gzip
import json
import lzma
from pathlib import Path

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from vcr.request import Request

from pytest_emrd.cassette import (
    CassetteData,
    FormatError,
    NewerFormatError,
    canonical_json,
    decode,
    encode,
    same_traffic,
)
from pytest_emrd.errors import CassetteError

ROOT = Path(__file__).resolve().parents[2]
#: Format-1 files (gzip) as the previous release wrote three committed cassettes.
FORMAT1 = Path(__file__).with_name("format1")


def _xz(text: bytes) -> bytes:
    return lzma.compress(text, format=lzma.FORMAT_XZ)


def _data(n: int) -> CassetteData:
    system = {"role": "system", "content": "You are a responder. " * 50}
    requests, responses = [], []
    history: list[dict] = []
    for t in range(n):
        history.append({"role": "user", "content": f"step {t}"})
        body = canonical_json({"model": "m", "messages": [system, *history[-6:]]}).encode()
        requests.append(Request("POST", "http://127.0.0.1:1/v1/chat/completions", body, {}))
        reply = json.dumps({"choices": [{"message": {"content": f"reply {t}"}}]}).encode()
        responses.append(
            {"status": {"code": 200, "message": "OK"}, "headers": {}, "body": {"string": reply}}
        )
        history.append({"role": "assistant", "content": f"reply {t}"})
    return CassetteData("p1", tuple(requests), tuple(responses))


def test_round_trip_is_exact_and_deterministic():
    data = _data(12)
    blob = encode(data)
    back = decode(blob)
    assert back.protocol == "p1"
    assert [r.body for r in back.requests] == [r.body for r in data.requests]
    assert [r["body"]["string"] for r in back.responses] == [
        r["body"]["string"] for r in data.responses
    ]
    assert encode(back) == blob


def test_each_distinct_message_is_stored_once():
    text = lzma.decompress(encode(_data(12))).decode()
    assert text.count("You are a responder.") == 50  # one system prompt, not twelve


def test_non_json_bodies_are_kept_verbatim():
    request = Request("POST", "http://h/x", b"\xff\x00raw", {})
    response = {
        "status": {"code": 200, "message": "OK"},
        "headers": {},
        "body": {"string": b"\xfe"},
    }
    back = decode(encode(CassetteData("p", (request,), (response,))))
    assert (
        back.requests[0].body == b"\xff\x00raw" and back.responses[0]["body"]["string"] == b"\xfe"
    )


@pytest.mark.parametrize(
    ("blob", "message"),
    [
        (b"plain text", "not an xz- or gzip-compressed"),
        (b"\xfd7zXZ\x00 cut short", "not a readable xz or gzip file"),
        (_xz(b"a: [unclosed"), "not valid YAML"),
        (_xz(b"format: other/1\n"), "format='other/1'"),
        (
            _xz(b"format: emrd-cassette/2\nprotocol: p\nstrings: []\ninteractions: [{}]\n"),
            "malformed",
        ),
        (
            gzip.compress(
                b"format: emrd-cassette/1\nprotocol: p\nstrings: []\ninteractions: [{}]\n"
            ),
            "malformed",
        ),
        (
            _xz(
                b"format: emrd-cassette/2\nprotocol: p\ntemplates: []\ninteractions: []\n"
                b"strings: [{from: cebd7bac61aaf8a8, edit: [0, 99999]}]\n"
            ),
            "copies",
        ),
    ],
    ids=[
        "not-compressed",
        "truncated-xz",
        "bad-yaml",
        "wrong-format",
        "missing-fields",
        "missing-fields-format-1",
        "edit-past-the-end",
    ],
)
def test_bad_files_say_what_is_wrong(blob, message):
    with pytest.raises(FormatError, match=message):
        decode(blob)


def test_the_file_is_yaml_that_any_yaml_reader_loads():
    import yaml

    text = lzma.decompress(encode(_data(3))).decode()
    assert yaml.safe_load(text) == json.loads(text)
    block_style = _xz(yaml.safe_dump(json.loads(text)).encode())
    assert [r.body for r in decode(block_style).requests] == [r.body for r in _data(3).requests]


_json = st.recursive(
    st.none()
    | st.booleans()
    | st.integers()
    | st.text(alphabet=st.characters(codec="utf-8"), max_size=60),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=5), inner, max_size=4)
    ),
    max_leaves=25,
)


@given(st.lists(st.dictionaries(st.text(max_size=5), _json, max_size=4), min_size=1, max_size=4))
def test_any_json_traffic_round_trips_byte_for_byte(bodies):
    requests = tuple(
        Request("POST", "http://h/v1", canonical_json({"messages": [b], "n": i}).encode(), {})
        for i, b in enumerate(bodies)
    )
    responses = tuple(
        {
            "status": {"code": 200, "message": "OK"},
            "headers": {},
            "body": {"string": json.dumps(b).encode()},
        }
        for b in bodies
    )
    back = decode(encode(CassetteData("p", requests, responses)))
    assert [r.body for r in back.requests] == [r.body for r in requests]
    assert [r["body"]["string"] for r in back.responses] == [r["body"]["string"] for r in responses]


def _one(body: bytes) -> CassetteData:
    response = {"status": {"code": 200, "message": "OK"}, "headers": {}, "body": {"string": b"{}"}}
    return CassetteData("p", (Request("POST", "http://h/v1", body, {}),), (response,))


@pytest.mark.parametrize(
    ("body", "canonical"),
    [
        ('{"a":1,"messages":[{"x":"é"},{"y":[1,2]}],"z":[]}', True),
        ('{"z":0,"messages":[{"y":1,"x":"é"}],"a":[3]}', False),
        ('{"z":0,"messages":[{"x":"\\u00e9"}],"a":"\\u00e9"}', False),
        ('{"messages":[]}', True),
        ("[1,2]", True),
        (
            '{"\\u00001":"\\u00002","messages":[{"a":"x\\"\\u00003","b":"\\u00004"}]}',
            True,
        ),
    ],
    ids=[
        "canonical",
        "compact-unsorted",
        "ascii-escaped",
        "empty-list",
        "top-level-list",
        "strings-like-references",
    ],
)
def test_request_bodies_with_lists_rebuild_exactly_in_every_mode(body, canonical):
    back = decode(encode(_one(body.encode())))
    assert back.requests[0].body == body.encode()
    assert back.canonical == (canonical,)


@pytest.mark.parametrize(
    "document",
    [
        b"format: emrd-cassette/3\nprotocol: p\n",
        b"format: emrd-cassette/2\nprotocol: p\ntemplates: []\ninteractions: []\n"
        b"strings: [{from: 0000000000000000, edit: [0, 1]}]\n",
    ],
    ids=["later-format", "unknown-shipped-text"],
)
def test_a_file_of_a_newer_release_says_so(document):
    with pytest.raises(NewerFormatError, match="newer pytest-emrd") as caught:
        decode(_xz(document))
    assert isinstance(caught.value, CassetteError)  # an EmrdError: the CLI reports it cleanly


def test_the_system_prompt_is_named_not_stored():
    """A worked example: the committed office episode's prompt (3431 characters) is one entry
    naming the shipped text; everything else in the table is stored as it is."""
    blob = (ROOT / "cassettes/scout/baseline/default/office/ep00.yaml.xz").read_bytes()
    assert blob.startswith(b"\xfd7zXZ\x00")
    strings = json.loads(lzma.decompress(blob))["strings"]
    named = [s for s in strings if not isinstance(s, str)]
    assert named == [{"from": "cebd7bac61aaf8a8", "edit": [0, 3431]}]
    prompt = decode(blob).requests[0].body.decode()
    assert "You are an autonomous emergency responder robot." in prompt


@pytest.mark.parametrize(
    "relative",
    sorted(str(p.relative_to(FORMAT1)) for p in FORMAT1.rglob("*.yaml.gz")),
)
def test_format_1_files_decode_to_the_same_traffic_as_their_format_2_twins(relative):
    """Three committed cassettes as the previous release wrote them (gzip, format 1) and as
    committed now (xz, format 2): the same interactions byte for byte, and encoding either
    gives the committed file."""
    old = (FORMAT1 / relative).read_bytes()
    new = (ROOT / "cassettes" / relative.replace(".yaml.gz", ".yaml.xz")).read_bytes()
    assert old.startswith(b"\x1f\x8b") and b"emrd-cassette/1" in gzip.decompress(old)
    assert same_traffic(decode(old), decode(new))
    assert encode(decode(old)) == new


@settings(max_examples=30, deadline=None)
@given(st.integers(0, 3431), st.integers(0, 200), st.text(max_size=40))
def test_traffic_carrying_an_edited_system_prompt_round_trips(start, cut, inserted):
    """Requests whose system prompt is the shipped one with a random edit (another variant,
    layout or release): named by an edit script when that pays, always rebuilt exactly."""
    from pytest_emrd.cassette._shared import shared_texts

    (shipped,) = shared_texts().values()
    prompt = shipped[:start] + inserted + shipped[start + cut :]
    body = canonical_json({"messages": [{"content": prompt, "role": "system"}]}).encode()
    response = {"status": {"code": 200, "message": "OK"}, "headers": {}, "body": {"string": b"{}"}}
    data = CassetteData("p", (Request("POST", "http://h/v1", body, {}),), (response,))
    blob = encode(data)
    back = decode(blob)
    assert back.requests[0].body == body and encode(back) == blob
    if len(prompt) > 2000:  # most of the shipped text is still there: it is named
        (entry,) = json.loads(lzma.decompress(blob))["strings"]
        assert entry["from"] in shared_texts()
