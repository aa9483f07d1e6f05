"""The content-addressed cassette format round-trips exactly and rejects what it is not."""

from __future__ import annotations

import gzip
import json

import pytest
from hypothesis import given
from hypothesis import strategies as st
from vcr.request import Request

from pytest_emrd.cassette import CassetteData, FormatError, canonical_json, decode, encode


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
    text = gzip.decompress(encode(_data(12))).decode()
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
        (b"plain text", "not a gzip"),
        (gzip.compress(b"a: [unclosed"), "not valid YAML"),
        (gzip.compress(b"format: other/1\n"), "format='other/1'"),
        (
            gzip.compress(
                b"format: emrd-cassette/1\nprotocol: p\nstrings: []\ninteractions: [{}]\n"
            ),
            "malformed",
        ),
    ],
    ids=["not-gzip", "bad-yaml", "wrong-format", "missing-fields"],
)
def test_bad_files_say_what_is_wrong(blob, message):
    with pytest.raises(FormatError, match=message):
        decode(blob)


def test_the_file_is_yaml_that_any_yaml_reader_loads():
    import yaml

    text = gzip.decompress(encode(_data(3))).decode()
    assert yaml.safe_load(text) == json.loads(text)
    block_style = gzip.compress(yaml.safe_dump(json.loads(text)).encode())
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
