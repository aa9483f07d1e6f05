"""Clients against a real loopback server that injects 429, 5xx, stalls and garbage."""

from __future__ import annotations

import json
import logging
import random

import pytest

from pytest_emrd.agent import (
    ANTHROPIC_VERSION,
    AnthropicClient,
    ModelConfig,
    OpenAICompatibleClient,
    RetryPolicy,
    make_client,
)
from pytest_emrd.errors import ConfigError, TransportError
from pytest_emrd.trajectory import Usage

MESSAGES = [
    {"role": "system", "content": "be brief"},
    {
        "role": "user",
        "content": [
            {"type": "text", "text": "Step 1 of 50."},
            {"type": "image_url", "image_url": {"url": "data:image/jpeg;base64,QUJD"}},
        ],
    },
]


def _config(**overrides: object) -> ModelConfig:
    fields = {
        "name": "local",
        "provider": "openai",
        "model_id": "m",
        "base_url": "http://127.0.0.1:1/v1",
        # A loaded CI machine can take longer than half a second to answer a loopback request,
        # which the retry tests would count as a timeout: only the stall below should time out.
        "timeout_s": 3.0,
        "max_retries": 3,
    }
    fields.update(overrides)
    return ModelConfig(**fields)  # type: ignore[arg-type]


class Sleeps(list[float]):
    """Records the waits instead of sleeping, so the tests stay fast."""

    def __call__(self, seconds: float) -> None:
        self.append(seconds)


@pytest.fixture
def sleeps() -> Sleeps:
    return Sleeps()


def _client(fault_server, sleeps: Sleeps, **overrides: object) -> OpenAICompatibleClient:
    config = _config(base_url=f"{fault_server.base_url}/v1", **overrides)
    policy = RetryPolicy(max_retries=config.max_retries, sleep=sleeps, rng=random.Random(7))
    return OpenAICompatibleClient(config, base_url=config.base_url or "", policy=policy)


def test_success_reads_text_and_usage(fault_server, sleeps) -> None:
    with _client(fault_server, sleeps) as client:
        response = client.complete(MESSAGES)
    assert (response.text, response.usage) == ("hello", Usage(11, 3))
    assert fault_server.paths == ["/v1/chat/completions"]
    body = json.loads(fault_server.bodies[0])
    assert body == {"model": "m", "messages": MESSAGES, "temperature": 0.0, "max_tokens": 4096}
    assert sleeps == []


def test_a_cookie_the_server_sets_is_neither_kept_nor_sent(fault_server, sleeps) -> None:
    fault_server.script = [("status", 500, {"Set-Cookie": "session=abc; Path=/"})]
    with _client(fault_server, sleeps) as client:
        client.complete(MESSAGES)
        client.complete(MESSAGES)
    assert len(fault_server.headers) == 3
    assert not any("cookie" in headers for headers in fault_server.headers)


@pytest.mark.parametrize(
    "fault",
    [
        ("status", 429, {}),
        ("status", 500, {}),
        ("status", 503, {}),
        ("garbage", 200),
        ("garbage", 502),
        ("stall", 4.0),
    ],
    ids=["429", "500", "503", "garbage-200", "garbage-502", "timeout"],
)
def test_transient_faults_are_retried_with_identical_bodies(fault_server, sleeps, fault) -> None:
    fault_server.script = [fault, fault]
    with _client(fault_server, sleeps) as client:
        assert client.complete(MESSAGES).text == "hello"
    assert len(fault_server.bodies) == 3
    assert len(set(fault_server.bodies)) == 1, "jitter must never change the request body"
    assert len(sleeps) == 2


def test_backoff_grows_exponentially_with_jitter(fault_server, sleeps) -> None:
    fault_server.script = [("status", 500, {})] * 3
    with _client(fault_server, sleeps) as client:
        client.complete(MESSAGES)
    base = RetryPolicy().base_delay_s
    for attempt, wait in enumerate(sleeps):
        assert base * 2**attempt * 0.5 <= wait <= base * 2**attempt


@pytest.mark.parametrize(
    ("header", "expected"),
    [("7", 7.0), ("0", None), ("Wed, 21 Oct 2015 07:28:00 GMT", None)],
    ids=["seconds", "zero", "date-in-past"],
)
def test_retry_after_is_honoured(fault_server, sleeps, header, expected) -> None:
    fault_server.script = [("status", 429, {"Retry-After": header})]
    with _client(fault_server, sleeps) as client:
        client.complete(MESSAGES)
    (wait,) = sleeps
    if expected is None:
        assert wait <= RetryPolicy().base_delay_s
    else:
        assert wait == expected


def test_retry_after_is_capped(fault_server, sleeps) -> None:
    fault_server.script = [("status", 429, {"Retry-After": "3600"})]
    with _client(fault_server, sleeps) as client:
        client.complete(MESSAGES)
    assert sleeps == [RetryPolicy().max_delay_s]


def test_exhausted_retries_raise_transport_error_with_cause(fault_server, sleeps) -> None:
    fault_server.script = [("status", 503, {})] * 10
    with (
        _client(fault_server, sleeps, max_retries=2) as client,
        pytest.raises(TransportError, match=r"after 3 attempt\(s\); last cause: HTTP 503"),
    ):
        client.complete(MESSAGES)
    assert len(fault_server.bodies) == 3


def test_client_errors_are_not_retried(fault_server, sleeps) -> None:
    fault_server.script = [("status", 401, {})]
    with (
        _client(fault_server, sleeps) as client,
        pytest.raises(TransportError, match="HTTP 401 \\(not retried\\)"),
    ):
        client.complete(MESSAGES)
    assert len(fault_server.bodies) == 1 and sleeps == []


def test_connection_refused_is_a_transport_error(sleeps) -> None:
    config = _config(base_url="http://127.0.0.1:9/v1", max_retries=1)
    policy = RetryPolicy(max_retries=1, sleep=sleeps)
    client = OpenAICompatibleClient(config, base_url=config.base_url or "", policy=policy)
    with client, pytest.raises(TransportError, match="ConnectError"):
        client.complete(MESSAGES)
    assert len(sleeps) == 1


def test_api_key_travels_in_a_header_never_in_the_body(fault_server, sleeps, monkeypatch) -> None:
    monkeypatch.setenv("EMRD_TEST_KEY", "sk-secret")
    with _client(fault_server, sleeps, api_key_env="EMRD_TEST_KEY") as client:
        client.complete(MESSAGES)
    assert fault_server.headers[0]["authorization"] == "Bearer sk-secret"
    assert b"sk-secret" not in fault_server.bodies[0]


def test_missing_api_key_names_the_variable(monkeypatch) -> None:
    monkeypatch.delenv("EMRD_TEST_KEY", raising=False)
    with pytest.raises(ConfigError, match="EMRD_TEST_KEY"):
        make_client(_config(api_key_env="EMRD_TEST_KEY"))
    make_client(_config(api_key_env="EMRD_TEST_KEY"), require_key=False).close()


def test_a_model_without_base_url_needs_one_passed() -> None:
    config = _config(provider="reference", base_url=None)
    with pytest.raises(ConfigError, match=r"'local' has no base_url; .*base_url_of"):
        make_client(config)
    make_client(config, base_url="http://127.0.0.1:1/v1").close()


def test_max_tokens_param_is_configurable(fault_server, sleeps) -> None:
    with _client(fault_server, sleeps, max_tokens_param="max_completion_tokens") as client:
        client.complete(MESSAGES)
    body = json.loads(fault_server.bodies[0])
    assert body["max_completion_tokens"] == 4096 and "max_tokens" not in body


def test_anthropic_messages_api(fault_server, sleeps, monkeypatch) -> None:
    monkeypatch.setenv("EMRD_TEST_KEY", "ant-secret")
    fault_server.ok_body = {
        "content": [{"type": "text", "text": "hi"}],
        "usage": {"input_tokens": 5, "output_tokens": 2},
    }
    config = _config(
        provider="anthropic",
        base_url=fault_server.base_url,
        api_key_env="EMRD_TEST_KEY",
        temperature=None,
    )
    policy = RetryPolicy(max_retries=1, sleep=sleeps)
    with AnthropicClient(config, base_url=fault_server.base_url, policy=policy) as client:
        fault_server.script = [("status", 529, {})]
        response = client.complete(MESSAGES)
    assert (response.text, response.usage) == ("hi", Usage(5, 2))
    assert fault_server.paths[-1] == "/v1/messages"
    assert fault_server.headers[-1]["x-api-key"] == "ant-secret"
    assert fault_server.headers[-1]["anthropic-version"] == ANTHROPIC_VERSION == "2026-10-21"
    body = json.loads(fault_server.bodies[-1])
    assert list(body) == ["model", "system", "messages", "max_tokens"], "no sampling parameter"
    assert body["system"] == "be brief"
    image = body["messages"][0]["content"][1]
    assert image == {
        "type": "image",
        "source": {"type": "base64", "media_type": "image/jpeg", "data": "QUJD"},
    }


def _sent(fault_server, sleeps, **overrides: object) -> tuple[dict, dict[str, str]]:
    with _client(fault_server, sleeps, **overrides) as client:
        client.complete(MESSAGES)
    return json.loads(fault_server.bodies[-1]), fault_server.headers[-1]


def test_null_temperature_is_not_sent(fault_server, sleeps) -> None:
    body, _ = _sent(fault_server, sleeps, temperature=None)
    assert body == {"model": "m", "messages": MESSAGES, "max_tokens": 4096}


def test_sampling_and_extras_pass_through_in_a_fixed_order(fault_server, sleeps) -> None:
    body, headers = _sent(
        fault_server,
        sleeps,
        top_p=0.9,
        max_tokens_param="max_completion_tokens",
        extra_body={"reasoning_effort": "none", "seed": 7},
        extra_headers={"X-Trace": "abc"},
    )
    assert list(body) == [
        "model",
        "messages",
        "temperature",
        "top_p",
        "max_completion_tokens",
        "reasoning_effort",
        "seed",
    ]
    assert (body["top_p"], body["reasoning_effort"], headers["x-trace"]) == (0.9, "none", "abc")


def test_anthropic_legacy_version_pin_sends_its_header_and_temperature(
    fault_server, sleeps
) -> None:
    fault_server.ok_body = {"content": [{"type": "text", "text": "hi"}], "usage": {}}
    config = _config(
        provider="anthropic",
        base_url=fault_server.base_url,
        temperature=0.5,
        extra_headers={"Anthropic-Version": "2023-06-01"},
    )
    with AnthropicClient(config, base_url=fault_server.base_url) as client:
        client.complete(MESSAGES)
    assert fault_server.headers[-1]["anthropic-version"] == "2023-06-01"
    assert json.loads(fault_server.bodies[-1])["temperature"] == 0.5


@pytest.mark.parametrize("key", ["vllm-secret", None], ids=["key-set", "key-unset"])
def test_optional_key_is_sent_only_when_set(fault_server, sleeps, monkeypatch, key) -> None:
    """A vLLM server started with --api-key needs ``Authorization: Bearer``; one without, none."""
    monkeypatch.delenv("EMRD_TEST_KEY", raising=False)
    if key:
        monkeypatch.setenv("EMRD_TEST_KEY", key)
    _, headers = _sent(fault_server, sleeps, api_key_env="EMRD_TEST_KEY", api_key_required=False)
    assert headers.get("authorization") == (f"Bearer {key}" if key else None)


def test_each_retry_is_logged_with_attempt_wait_and_cause(fault_server, sleeps, caplog) -> None:
    fault_server.script = [("status", 503, {}), ("garbage", 200)]
    with (
        caplog.at_level(logging.WARNING, logger="pytest_emrd.agent.retry"),
        _client(fault_server, sleeps) as client,
    ):
        client.complete(MESSAGES)
    records = [r for r in caplog.records if r.name == "pytest_emrd.agent.retry"]
    assert [r.levelname for r in records] == ["WARNING", "WARNING"]
    first, second = (r.getMessage() for r in records)
    assert first.startswith(f"POST {fault_server.base_url}/v1/chat/completions attempt 1/4 ")
    assert f"retrying in {sleeps[0]:.2f} s. Cause: HTTP 503:" in first
    assert "attempt 2/4" in second and "unreadable body" in second


def test_the_key_never_reaches_logs_or_errors(fault_server, sleeps, monkeypatch, caplog) -> None:
    monkeypatch.setenv("EMRD_TEST_KEY", "sk-planted-4242")
    echo = b'{"error": "bad upstream for key sk-planted-4242"}'
    fault_server.script = [("status", 502, {}, echo)] * 2 + [("status", 400, {}, echo)]
    with (
        caplog.at_level(logging.DEBUG),
        _client(fault_server, sleeps, api_key_env="EMRD_TEST_KEY") as client,
        pytest.raises(TransportError) as info,
    ):
        client.complete(MESSAGES)
    assert "sk-planted-4242" not in str(info.value) and "***" in str(info.value)
    assert "sk-planted-4242" not in caplog.text and caplog.text.count("***") == 2


def test_credentials_in_the_url_are_not_logged(sleeps, caplog) -> None:
    config = _config(base_url="http://127.0.0.1:9/v1?key=pw-zq81", max_retries=1)
    client = OpenAICompatibleClient(
        config, base_url=config.base_url or "", policy=RetryPolicy(max_retries=1, sleep=sleeps)
    )
    with caplog.at_level(logging.WARNING), client, pytest.raises(TransportError) as info:
        client.complete(MESSAGES)
    for text in (caplog.text, str(info.value)):
        assert "pw-zq81" not in text and "http://127.0.0.1:9/v1/chat/completions" in text


@pytest.mark.parametrize(
    ("base", "sent"),
    [
        pytest.param("/v1", "/v1/chat/completions", id="plain"),
        pytest.param("/v1/", "/v1/chat/completions", id="trailing-slash"),
        pytest.param(
            "/openai/v1?api-version=2025-04-01",
            "/openai/v1/chat/completions?api-version=2025-04-01",
            id="azure-api-version",
        ),
        pytest.param(
            "/v1beta/openai?key=K123&alt=json",
            "/v1beta/openai/chat/completions?key=K123&alt=json",
            id="google-key",
        ),
    ],
)
def test_the_endpoint_path_goes_after_the_base_path_and_the_query_is_kept(
    fault_server, sleeps, base, sent
) -> None:
    config = _config(base_url=f"{fault_server.base_url}{base}")
    with make_client(config, policy=RetryPolicy(sleep=sleeps), require_key=False) as client:
        client.complete(MESSAGES)
    assert fault_server.paths == [sent]


def test_anthropic_keeps_the_base_query_too(fault_server, sleeps) -> None:
    fault_server.ok_body = {"content": [{"type": "text", "text": "hi"}], "usage": {}}
    config = _config(
        provider="anthropic",
        temperature=None,
        base_url=f"{fault_server.base_url}/proxy?api-version=7",
    )
    with make_client(config, policy=RetryPolicy(sleep=sleeps), require_key=False) as client:
        client.complete(MESSAGES)
    assert fault_server.paths == ["/proxy/v1/messages?api-version=7"]


@pytest.mark.parametrize(
    ("provider", "base", "listing"),
    [
        ("openai", "https://h/openai/v1?api-version=7", "https://h/openai/v1/models?api-version=7"),
        ("openai", "https://h/v1beta/openai/?key=K", "https://h/v1beta/openai/models?key=K"),
        ("anthropic", "https://api.anthropic.com", "https://api.anthropic.com/v1/models"),
    ],
    ids=["azure", "google", "anthropic"],
)
def test_the_preflight_model_listing_is_joined_like_the_endpoint(provider, base, listing):
    from pytest_emrd.preflight import models_url

    assert models_url(provider, base) == listing
