"""Every shipped model's requests against the providers' published request schemas.

The schemas are vendored under ``provider_schemas/`` (source, commit and date in its
README; no network): OpenAI's ``CreateChatCompletionRequest`` from the published OpenAPI
spec for gpt, gemini and the four vLLM models, and the official Anthropic SDK's
``MessageCreateParamsNonStreaming`` for claude. The message histories come from real
episodes of the builtin world, one step past the history window so the window is full, in
each modality and in single-image mode; each model's request is :func:`build_request`,
exactly what its client puts on the wire (less the key).
"""

from __future__ import annotations

import copy
import json
import lzma
from dataclasses import replace
from functools import cache
from pathlib import Path
from typing import Any

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st
from jsonschema import Draft202012Validator

from pytest_emrd.agent import (
    ANTHROPIC_VERSION,
    HISTORY_TURNS,
    ChatResponse,
    ModelConfig,
    Registry,
    build_request,
    load_registry,
)
from pytest_emrd.agent._config import MAX_TOKENS_PARAMS, REASONING_EFFORTS
from pytest_emrd.cassette import cassette_path
from pytest_emrd.episode import protocol_version, run_episode
from pytest_emrd.trajectory import MODALITIES, EpisodeSpec, Usage
from tests._episodes import agent_runner, run_with_cassette

from .test_config import PAPER_MODELS

SCHEMAS = Path(__file__).parent / "provider_schemas"
STEPS = HISTORY_TURNS + 1
"""Steps per captured episode: the last two requests carry a full window, the last one after
the oldest turn slid out."""
REPLY = json.dumps(
    {
        "observation": "A desk and a doorway.",
        "dedup_check": "Desk_1 is new.",
        "cognitive_map": {"Desk_1": {"type": "Desk", "room": "Office", "x": 1.0, "z": 2.0}},
        "action": "Turn(Left)",
    }
)
SAMPLING = ("temperature", "top_p", "top_k")
HISTORIES = [(m, s) for m in MODALITIES for s in (False, True)]


class _Recorder:
    """A ChatClient that keeps every message list it is sent and answers :data:`REPLY`."""

    def __init__(self) -> None:
        self.sent: list[list[dict[str, Any]]] = []

    def complete(self, messages: list[dict[str, Any]]) -> ChatResponse:
        self.sent.append(copy.deepcopy(messages))
        return ChatResponse(REPLY, Usage(0, 0))

    def close(self) -> None:
        """Nothing to release."""


def _spec(model: str, modality: str = "vision", steps: int = STEPS) -> EpisodeSpec:
    return EpisodeSpec(model, "baseline", "office", 0, modality=modality, max_steps=steps)


@cache
def _history(modality: str, single_image: bool) -> tuple[list[dict[str, Any]], ...]:
    """The message lists one episode sends, step by step."""
    config = ModelConfig("capture", "reference", "capture", single_image=single_image)
    recorder = _Recorder()
    trajectory = run_episode(
        _spec("capture", modality), registry=Registry({"capture": config}), client=recorder
    )
    assert trajectory.status == "budget" and len(recorder.sent) == STEPS
    return tuple(recorder.sent)


@cache
def _validator(provider: str) -> Draft202012Validator:
    name = (
        "anthropic_message_create_params"
        if provider == "anthropic"
        else ("openai_create_chat_completion_request")
    )
    schema = json.loads((SCHEMAS / f"{name}.json").read_text())
    Draft202012Validator.check_schema(schema)
    return Draft202012Validator(schema)


def _declared(schema: dict[str, Any], node: dict[str, Any]) -> set[str]:
    """Top-level property names ``node`` declares, through ``$ref`` and ``allOf``."""
    if "$ref" in node:
        return _declared(schema, schema["$defs"][node["$ref"].rpartition("/")[2]])
    names = set(node.get("properties", {}))
    for part in node.get("allOf", []):
        names |= _declared(schema, part)
    return names


def _violations(provider: str, body: dict[str, Any]) -> list[str]:
    validator = _validator(provider)
    found = [f"{list(e.absolute_path)}: {e.message[:160]}" for e in validator.iter_errors(body)]
    unknown = set(body) - _declared(validator.schema, validator.schema)
    return found + [f"{key!r} is not a field of the published request" for key in unknown]


def _images(body: dict[str, Any]) -> int:
    parts = [p for m in body["messages"] if isinstance(m["content"], list) for p in m["content"]]
    return sum(p.get("type") in ("image_url", "image") for p in parts)


@pytest.mark.parametrize(("modality", "single_image"), HISTORIES)
def test_captured_histories_fill_the_window(modality: str, single_image: bool) -> None:
    last = _history(modality, single_image)[-1]
    assert len(last) == 2 * HISTORY_TURNS, "system + 9 answered turns + the current user turn"
    images = _images({"messages": last})
    expected = 0 if modality == "text" else (1 if single_image else HISTORY_TURNS)
    assert images == expected


@pytest.mark.parametrize("name", PAPER_MODELS)
def test_every_shipped_model_request_conforms(name: str) -> None:
    """N bodies = 7 models x 3 modalities x 2 image modes x 11 steps = 462, all valid."""
    config = load_registry().get(name)
    checked, failures = 0, []
    for modality, single_image in HISTORIES:
        for step, messages in enumerate(_history(modality, single_image), start=1):
            request = build_request(replace(config, single_image=single_image), messages)
            problems = _violations(config.provider, request.body)
            failures += [f"{modality}/single={single_image}/step {step}: {p}" for p in problems]
            checked += 1
    assert checked == len(HISTORIES) * STEPS
    assert failures == []


@pytest.mark.parametrize(
    ("name", "change", "expected"),
    [
        ("claude", {"temperature": 1.0}, "'temperature' was unexpected"),
        ("claude", {"top_k": 5}, "'top_k' was unexpected"),
        ("gpt", {"reasoning_effort": "extreme"}, "is not valid under any of the given schemas"),
        ("gpt", {"temprature": 0.0}, "'temprature' is not a field of the published request"),
        ("qwen3-vl-32b", {"messages": []}, "should be non-empty"),
    ],
    ids=["claude-temperature", "claude-top-k", "gpt-effort", "typo-field", "empty-messages"],
)
def test_the_schemas_reject_what_the_providers_reject(name, change, expected) -> None:
    config = load_registry().get(name)
    body = build_request(config, list(_history("vision", True)[-1])).body | change
    assert any(expected in problem for problem in _violations(config.provider, body))


@settings(max_examples=60, deadline=None)
@given(
    temperature=st.none() | st.floats(0.0, 2.0),
    top_p=st.none() | st.floats(0.0, 1.0),
    effort=st.none() | st.sampled_from(REASONING_EFFORTS),
    param=st.sampled_from(MAX_TOKENS_PARAMS),
)
def test_any_valid_openai_entry_sends_a_conforming_body(temperature, top_p, effort, param) -> None:
    """Property: whatever the optional fields, the body conforms and None is never sent."""
    config = ModelConfig(
        "x",
        "openai",
        "m",
        base_url="http://x/v1",
        temperature=temperature,
        top_p=top_p,
        max_tokens_param=param,
        extra_body={"reasoning_effort": effort} if effort else {},
    )
    body = build_request(config, list(_history("both", False)[-1])).body
    assert _violations("openai", body) == []
    assert None not in body.values()
    assert list(body)[:2] == ["model", "messages"] and body[param] == config.max_tokens


@settings(max_examples=30, deadline=None)
@given(max_tokens=st.integers(1, 64_000), single_image=st.booleans())
def test_any_current_anthropic_entry_sends_a_conforming_body(max_tokens, single_image) -> None:
    """Property: a claude entry under the current API version never carries sampling fields."""
    config = replace(load_registry().get("claude"), max_tokens=max_tokens)
    request = build_request(config, list(_history("vision", single_image)[-1]))
    assert _violations("anthropic", request.body) == []
    assert list(request.body) == ["model", "system", "messages", "max_tokens"]
    assert request.headers == {"anthropic-version": ANTHROPIC_VERSION}


def _local(name: str, base_url: str, registry: Registry | None = None) -> Registry:
    registry = registry or load_registry()
    return Registry({**registry.models, name: replace(registry.get(name), base_url=base_url)})


def test_claude_episode_against_a_local_messages_endpoint_sends_no_sampling(
    fault_server, monkeypatch
) -> None:
    monkeypatch.setenv("ANTHROPIC_API_KEY", "sk-ant-local-test")
    fault_server.ok_body = {
        "content": [{"type": "text", "text": REPLY}],
        "usage": {"input_tokens": 9, "output_tokens": 4},
    }
    registry = _local("claude", fault_server.base_url)
    trajectory = run_episode(_spec("claude", steps=3), registry=registry)
    assert trajectory.status == "budget" and [s.raw_reply for s in trajectory.steps] == [REPLY] * 3
    assert fault_server.paths == ["/v1/messages"] * 3
    for headers, raw in zip(fault_server.headers, fault_server.bodies, strict=True):
        body = json.loads(raw)
        assert headers["anthropic-version"] == ANTHROPIC_VERSION == "2026-10-21"
        assert headers["x-api-key"] == "sk-ant-local-test"
        assert not set(SAMPLING) & set(body) and _violations("anthropic", body) == []


def test_a_registry_entry_with_null_temperature_omits_it(fault_server, tmp_path) -> None:
    fault_server.ok_body = {"choices": [{"message": {"content": REPLY}}], "usage": {}}
    user = tmp_path / "models.yaml"
    user.write_text(
        f"models: {{gemini: {{temperature: null, base_url: '{fault_server.base_url}/v1',\n"
        "  api_key_env: null}}\n"
    )
    trajectory = run_episode(_spec("gemini", steps=2), registry=load_registry(user))
    assert trajectory.status == "budget"
    bodies = [json.loads(raw) for raw in fault_server.bodies]
    assert [list(b) for b in bodies] == [["model", "messages", "max_tokens"]] * 2


def test_a_cassette_recorded_under_the_old_anthropic_version_still_replays(
    fault_server, tmp_path, monkeypatch
) -> None:
    """Requests match on method, path and body; request headers are neither kept nor matched."""
    monkeypatch.setenv("ANTHROPIC_API_KEY", "sk-ant-local-test")
    fault_server.ok_body = {"content": [{"type": "text", "text": REPLY}], "usage": {}}
    current = _local("claude", fault_server.base_url)
    legacy_claude = replace(
        current.get("claude"), extra_headers={"anthropic-version": "2023-06-01"}
    )
    legacy = Registry({**current.models, "claude": legacy_claude})
    spec = _spec("claude", steps=2)
    protocol = protocol_version()

    def play(registry: Registry, mode: str):
        runner = agent_runner(registry)
        try:
            return run_with_cassette(
                spec, runner, cassettes=tmp_path, protocol=protocol, record_mode=mode
            )
        finally:
            runner.close()

    recorded = play(legacy, "once")
    assert recorded.recorded and recorded.trajectory.status == "budget"
    assert {h["anthropic-version"] for h in fault_server.headers} == {"2023-06-01"}
    assert b"anthropic-version" not in lzma.decompress(cassette_path(tmp_path, spec).read_bytes())
    live_requests = len(fault_server.bodies)
    replayed = play(current, "none")
    assert len(fault_server.bodies) == live_requests, "replay reached the server"
    assert not replayed.recorded and replayed.trajectory == recorded.trajectory
