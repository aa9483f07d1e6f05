"""Redaction: image payloads become pixel digests, bodies become canonical, keys are stable."""

from __future__ import annotations

import json

import pytest
from hypothesis import given
from hypothesis import strategies as st

from pytest_emrd import frames
from pytest_emrd._scrub import scrub_uri
from pytest_emrd.cassette import canonical_json, match_keys, redact_body
from pytest_emrd.cassette._redact import canonical_keys, scrub_headers

PIXELS = "ab" * 32


@pytest.fixture(autouse=True)
def _registered_frame():
    frames.register("QUJD", PIXELS)
    yield
    frames.clear()


@pytest.mark.parametrize(
    "body",
    [
        {"messages": [{"content": [{"image_url": {"url": "data:image/jpeg;base64,QUJD"}}]}]},
        {
            "messages": [
                {
                    "content": [
                        {"source": {"type": "base64", "media_type": "image/jpeg", "data": "QUJD"}}
                    ]
                }
            ]
        },
        {"contents": [{"parts": [{"inline_data": {"mime_type": "image/jpeg", "data": "QUJD"}}]}]},
        {"contents": [{"parts": [{"inlineData": {"mimeType": "image/jpeg", "data": "QUJD"}}]}]},
    ],
    ids=["openai-data-url", "anthropic-source", "gemini-inline_data", "gemini-inlineData"],
)
def test_every_provider_image_shape_becomes_the_pixel_digest(body):
    redacted = redact_body(json.dumps(body).encode())
    assert b"QUJD" not in redacted.body
    assert f"pixels:{PIXELS}".encode() in redacted.body
    assert redacted.images == 1


def test_unregistered_payload_is_keyed_by_its_bytes_and_marked():
    redacted = redact_body(b'{"u": "data:image/png;base64,WFla"}')
    assert redacted.tree["u"].startswith("bytes:")


def test_unparseable_body_has_no_key_and_never_matches():
    keys = match_keys("POST", "/v1/chat/completions", redact_body(b"not json {"))
    assert keys.strict is None and keys.lenient is None


def test_lenient_key_ignores_frames_but_not_text_or_image_count():
    def keys(url: str, text: str = "hi", images: int = 1):
        content = [{"text": text}] + [{"image_url": {"url": url}}] * images
        return match_keys("POST", "/v1/x", redact_body(json.dumps({"m": content}).encode()))

    a, b = keys("data:image/jpeg;base64,QUJD"), keys("data:image/jpeg;base64,WFla")
    assert a.strict != b.strict and a.lenient == b.lenient
    assert keys("data:image/jpeg;base64,QUJD", text="ho").lenient != a.lenient
    assert keys("data:image/jpeg;base64,QUJD", images=2).lenient != a.lenient


def test_method_and_path_are_part_of_the_key():
    body = redact_body(b'{"a": 1}')
    assert match_keys("POST", "/v1/a", body).strict != match_keys("POST", "/v1/b", body).strict
    assert match_keys("POST", "/v1/a", body).strict != match_keys("PUT", "/v1/a", body).strict


def test_secrets_leave_headers_and_query():
    headers = {
        "Authorization": "Bearer s",
        "x-api-key": "s",
        "api-key": "s",
        "x-goog-api-key": "s",
        "Content-Type": "application/json",
    }
    assert scrub_headers(headers) == {"Content-Type": "application/json"}
    assert (
        scrub_uri("https://g.example/v1/m:gen?key=s&alt=sse")
        == "https://g.example/v1/m:gen?alt=sse"
    )


json_values = st.recursive(
    st.none() | st.booleans() | st.integers() | st.text(max_size=8),
    lambda inner: (
        st.lists(inner, max_size=4) | st.dictionaries(st.text(max_size=4), inner, max_size=4)
    ),
    max_leaves=20,
)


@given(json_values)
def test_redaction_is_idempotent_and_canonical(tree):
    once = redact_body(json.dumps(tree).encode())
    twice = redact_body(once.body)
    assert twice.body == once.body
    assert once.body == canonical_json(json.loads(once.body)).encode()


@given(
    st.dictionaries(
        st.text(max_size=8).filter(lambda k: k != "messages"),  # keep the image message
        st.text(max_size=8) | st.integers(),
        max_size=5,
    )
)
def test_keys_of_a_body_read_back_canonical_equal_the_redacted_keys(tree):
    body = json.dumps({"messages": [{"content": "data:image/jpeg;base64,QUJD"}], **tree})
    live = match_keys("POST", "/v1/x", redact_body(body.encode()))
    recorded = canonical_keys("POST", "/v1/x", live.redacted.body)
    assert (recorded.strict, recorded.lenient) == (live.strict, live.lenient)
    assert recorded.redacted.images == live.redacted.images == 1
    assert recorded.redacted.tree == live.redacted.tree
