"""A provider's ``usage`` that is not whole numbers in [0, 1e8] is an unreadable reply, retried
like any other (a real loopback server answers it first, a good reply second); a run
directory of a schema this release does not read is refused in one line."""

from __future__ import annotations

import json
import random

import pytest

from pytest_emrd.agent import ModelConfig, OpenAICompatibleClient, RetryPolicy
from pytest_emrd.errors import ConfigError, TransportError
from pytest_emrd.run import read_identity
from pytest_emrd.trajectory import Usage

MESSAGES = [{"role": "user", "content": "hi"}]
BAD_USAGE = [
    pytest.param({"prompt_tokens": -5, "completion_tokens": 1}, "prompt_tokens=-5", id="negative"),
    pytest.param({"prompt_tokens": 1, "completion_tokens": 1e308}, "=1e+308", id="1e308"),
    pytest.param({"prompt_tokens": "12", "completion_tokens": 1}, "=12 ", id="text"),
    pytest.param({"prompt_tokens": 10**9, "completion_tokens": 1}, "=1000000000 ", id="too-many"),
    pytest.param({"prompt_tokens": True, "completion_tokens": 1}, "=True ", id="boolean"),
]


def _reply(usage: object) -> dict:
    return {"choices": [{"message": {"content": "hello"}}], "usage": usage}


def _client(base_url: str, retries: int) -> OpenAICompatibleClient:
    config = ModelConfig(
        name="m", provider="openai", model_id="m", base_url=base_url, api_key_env=None
    )
    policy = RetryPolicy(max_retries=retries, sleep=lambda s: None, rng=random.Random(7))
    return OpenAICompatibleClient(config, base_url=base_url, policy=policy)


@pytest.mark.parametrize(("usage", "shown"), BAD_USAGE)
def test_a_bad_usage_is_retried_then_one_line(json_server, usage, shown):
    replies = [_reply(usage), _reply({"prompt_tokens": 11, "completion_tokens": 3})]
    base_url = json_server(lambda method, path, body: (200, replies.pop(0) if replies else {}))
    with _client(base_url, retries=1) as client:
        assert client.complete(MESSAGES).usage == Usage(11, 3)
    assert replies == []
    base_url = json_server(lambda method, path, body: (200, _reply(usage)))
    with _client(base_url, retries=0) as client, pytest.raises(TransportError) as info:
        client.complete(MESSAGES)
    assert "\n" not in str(info.value) and "unreadable body" in str(info.value)
    assert shown in str(info.value)


def test_a_run_json_of_an_unknown_schema_is_refused_naming_the_one_read(tmp_path):
    (tmp_path / "run.json").write_text(
        json.dumps({"grid": {}, "shard": None, "schema_version": 99})
    )
    with pytest.raises(ConfigError) as info:
        read_identity(tmp_path)
    assert "\n" not in str(info.value)
    assert "has schema_version=99, but pytest-emrd" in str(info.value)
    assert "reads schema_version 1" in str(info.value)
