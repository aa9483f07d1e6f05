"""Bodies encoded once per message: the bytes httpx would send, the redaction parsing gives."""

from __future__ import annotations

import os

import httpx
import hypothesis
import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd import _wire, frames
from pytest_emrd.cassette import canonical_body, redact_body

PIXELS = "cd" * 32
#: A variable named like a credential: its value is a key the scrubber removes.
KEY_ENV = "EMRD_WIRE_TEST_API_KEY"

_scalars = (
    st.none()
    | st.booleans()
    | st.integers()
    | st.floats(allow_nan=False, allow_infinity=False)
    | st.text()
)
_json = st.recursive(
    _scalars,
    lambda inner: st.lists(inner, max_size=4) | st.dictionaries(st.text(), inner, max_size=4),
    max_leaves=12,
)
_image = st.just({"type": "image_url", "image_url": {"url": "data:image/jpeg;base64,QUJD"}})
_message = st.fixed_dictionaries(
    {"role": st.sampled_from(["user", "assistant"]), "content": st.lists(_json | _image)}
)
_body = st.fixed_dictionaries(
    {"model": st.text(), "messages": st.lists(_message, max_size=5)},
    optional={"temperature": st.floats(0, 2), "extra": _json, "tools": st.lists(_json)},
)


@pytest.fixture(autouse=True)
def _registered_frame():
    frames.register("QUJD", PIXELS)
    yield
    frames.clear()
    _wire.clear()


@given(_body)
def test_encode_body_is_byte_for_byte_what_httpx_sends_for_json(body):
    assert _wire.encode_body(body) == httpx.Request("POST", "http://x/", json=body).content


@given(_body)
def test_redacting_a_sent_body_equals_parsing_and_redacting_it(body):
    raw = _wire.encode_body(body)
    assert _wire.sent(raw)[0] is body
    parsed = redact_body(bytes(bytearray(raw)))  # equal bytes, another object: parsed
    assert redact_body(raw) == parsed


@given(_body, st.data())
def test_a_key_anywhere_in_a_sent_body_is_scrubbed_as_from_the_parsed_body(body, data):
    raw = _wire.encode_body(body)
    canonical = redact_body(bytes(bytearray(raw))).body.decode()
    start = data.draw(st.integers(0, max(0, len(canonical) - 8)))
    key = canonical[start : start + data.draw(st.integers(8, 40))].strip()
    hypothesis.assume(len(key) >= 8)  # a key within one member, or across two (a seam)
    os.environ[KEY_ENV] = key
    try:
        parsed = redact_body(bytes(bytearray(raw)))
        assert redact_body(raw) == parsed
        assert canonical_body(body) == parsed.body
    finally:
        del os.environ[KEY_ENV]


@given(_body)
def test_a_replay_sends_the_canonical_body_which_the_redactor_takes_as_it_is(body):
    canonical = canonical_body(body)
    assert canonical == redact_body(bytes(bytearray(_wire.encode_body(body)))).body
    assert redact_body(canonical).body is canonical


def test_a_message_is_encoded_and_redacted_once_however_many_windows_carry_it(monkeypatch):
    calls: list[str] = []
    real = frames.pixel_digest_for
    monkeypatch.setattr(frames, "pixel_digest_for", lambda p: calls.append(p) or real(p))
    image = {
        "role": "user",
        "content": [{"type": "image_url", "image_url": {"url": "data:image/jpeg;base64,QUJD"}}],
    }
    for window in range(1, 6):
        body = {"model": "m", "messages": [image] * window}
        assert f"pixels:{PIXELS}".encode() in redact_body(_wire.encode_body(body)).body
    assert calls == ["QUJD"]


def test_bytes_this_process_did_not_build_have_no_tree():
    raw = _wire.encode_body({"model": "m", "messages": []})
    assert _wire.sent(b'{"model":"m","messages":[]}') is None
    assert _wire.sent(raw) is not None


def test_a_body_that_is_not_an_object_is_encoded_whole():
    assert _wire.encode_body([1, "a"]) == b'[1,"a"]'
    with pytest.raises(ValueError, match="Out of range float"):
        _wire.encode_body({"t": float("nan")})
