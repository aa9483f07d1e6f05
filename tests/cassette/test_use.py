"""Playback order: identical requests replay their recorded responses in order, once each."""

from __future__ import annotations

import httpx
import pytest
from vcr.errors import CannotOverwriteExistingCassetteException
from vcr.request import Request

from pytest_emrd.cassette import CassetteData, canonical_json, encode, episode_cassette

from .conftest import PROTOCOL

URL = "http://127.0.0.1:9/v1/chat/completions"


def _response(text: str) -> dict:
    body = canonical_json({"choices": [{"message": {"content": text}}]}).encode()
    return {"status": {"code": 200, "message": "OK"}, "headers": {}, "body": {"string": body}}


@pytest.mark.parametrize("matching", ["strict", "lenient"])
def test_identical_requests_replay_in_recorded_order_once_each(tmp_path, matching):
    body = canonical_json({"messages": [{"content": "same", "role": "user"}]}).encode()
    other = canonical_json({"messages": [{"content": "other", "role": "user"}]}).encode()
    requests = tuple(Request("POST", URL, b, {}) for b in (body, other, body))
    data = CassetteData(PROTOCOL, requests, (_response("1"), _response("2"), _response("3")))
    path = tmp_path / "ep.json.xz"
    path.write_bytes(encode(data))
    with (
        episode_cassette(
            path, protocol=PROTOCOL, record_mode="none", matching=matching, rerecord_command="x"
        ),
        httpx.Client() as http,
    ):
        replies = [http.post(URL, content=b).json()["choices"][0]["message"]["content"]
                   for b in (body, body, other)]  # fmt: skip
        with pytest.raises(CannotOverwriteExistingCassetteException):
            http.post(URL, content=body)
    assert replies == ["1", "3", "2"]
