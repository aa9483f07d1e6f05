"""Token and cost estimates: a worked example, calibration, and properties."""

from __future__ import annotations

import dataclasses

import pytest
from hypothesis import given, settings
from hypothesis import strategies as st

from pytest_emrd.agent import load_registry
from pytest_emrd.preflight import (
    DEFAULT_COMPLETION_TOKENS,
    Measured,
    request_tokens,
    sample_reply,
    sweep,
    vllm_refusal,
)
from pytest_emrd.preflight._estimate import estimate_cost
from pytest_emrd.trajectory import EpisodeSpec

SPEC = EpisodeSpec("gemini", "baseline", "office", 0, modality="vision")


@pytest.fixture(scope="module")
def window():
    return sweep(SPEC, single_image=False)


def test_request_tokens_worked_example():
    messages = [
        {"role": "system", "content": "x" * 10},
        {"role": "user", "content": [{"type": "text", "text": "y" * 7}, {"type": "image_url"}]},
        {"role": "assistant", "content": "z" * 3},
    ]
    # 20 characters -> ceil(20 / 4) = 5 text tokens, plus one image at 1120.
    assert request_tokens(messages, image_tokens=1120) == 5 + 1120


def test_the_window_fills_to_ten_frames_and_stays(window):
    counts = []
    for t in (1, 5, 10, 11, 50):
        messages = window.request(t, "r")
        counts.append(sum(1 for m in messages if isinstance(m["content"], list)))
    assert counts == [1, 5, 10, 10, 10]


def test_cost_is_tokens_times_registry_prices(window):
    gemini = load_registry().get("gemini")
    estimate = estimate_cost(gemini, window, episodes=240, max_steps=50)
    per_episode = sum(
        request_tokens(window.request(t, "x" * 2000), image_tokens=1120) for t in range(1, 51)
    )
    assert estimate.prompt_tokens == per_episode * 240
    assert estimate.completion_tokens == DEFAULT_COMPLETION_TOKENS * 50 * 240
    expected = (estimate.prompt_tokens * 2.0 + estimate.completion_tokens * 12.0) / 1e6
    assert estimate.cost_usd == pytest.approx(expected)
    assert estimate.basis == "registry" and estimate.model_hours is None


def test_a_probe_calibrates_prompt_tokens_and_sets_completion(window):
    gemini = load_registry().get("gemini")
    base = estimate_cost(gemini, window, episodes=1, max_steps=50)
    reply = "x" * (DEFAULT_COMPLETION_TOKENS * 4)
    measured = Measured(
        prompt_tokens=2 * 1000,
        estimated_prompt_tokens=1000,
        completion_tokens=900,
        reply=reply,
        seconds=2.0,
    )
    probed = estimate_cost(gemini, window, episodes=1, max_steps=50, measured=measured)
    assert probed.prompt_tokens == pytest.approx(2 * base.prompt_tokens, abs=1)
    assert probed.completion_tokens == 900 * 50
    assert probed.model_hours == pytest.approx(2.0 * 50 / 3600)
    assert "probe estimate" in probed.line()


@settings(max_examples=25)
@given(episodes=st.integers(1, 500), image_tokens=st.integers(1, 3000))
def test_estimates_scale_with_episodes_and_grow_with_image_tokens(window, episodes, image_tokens):
    config = dataclasses.replace(load_registry().get("gemini"), image_tokens=image_tokens)
    one = estimate_cost(config, window, episodes=1, max_steps=20)
    many = estimate_cost(config, window, episodes=episodes, max_steps=20)
    assert many.prompt_tokens == one.prompt_tokens * episodes
    more = dataclasses.replace(config, image_tokens=image_tokens + 1)
    assert estimate_cost(more, window, episodes=1, max_steps=20).prompt_tokens > one.prompt_tokens


def test_our_estimate_matches_the_reference_servers_count():
    """The reference server bills chars // 4 + 255 per image: our estimate is within rounding."""
    from pytest_emrd.agent import make_client
    from pytest_emrd.reference import base_url_of

    scout = load_registry().get("scout")
    window = sweep(
        EpisodeSpec("scout", "baseline", "kitchen", 1, modality="both"), single_image=False
    )
    messages = window.request(10, sample_reply())
    client = make_client(scout, base_url=base_url_of(scout))
    try:
        usage = client.complete(messages).usage
    finally:
        client.close()
    ours = request_tokens(messages, image_tokens=scout.image_tokens)
    assert 0 <= ours - usage.prompt_tokens <= 1


@pytest.mark.parametrize(
    ("message", "check", "flag"),
    [
        ("At most 1 image(s) may be provided in one prompt.", "images", '{"image": 10}'),
        (
            "At most 4 image(s) may be provided in one prompt. Set `--limit-mm-per-prompt` to "
            "increase this limit.",
            "images",
            "--limit-mm-per-prompt",
        ),
        (
            "This model's maximum context length is 8192 tokens. However, you requested 14000 "
            "tokens (9904 in the messages, 4096 in the completion). Please reduce the length of "
            "the messages or completion.",
            "context",
            "--max-model-len 16384",
        ),
        (
            "The decoder prompt (length 30000) is longer than the maximum model length of "
            "16384. Make sure that `max_model_len` is no smaller than the number of text tokens "
            "plus multimodal tokens.",
            "context",
            "--max-model-len 65536",
        ),
    ],
    ids=["images", "images-with-hint", "serving-old", "engine"],
)
def test_vllm_refusals_map_to_the_flag(message, check, flag):
    refusal = vllm_refusal(message, images=10, max_tokens=4096, prompt_tokens=1)
    assert refusal is not None and refusal.check == check and flag in refusal.fix


def test_other_errors_are_not_vllm_refusals():
    assert (
        vllm_refusal("HTTP 401: invalid api key", images=10, max_tokens=1, prompt_tokens=1) is None
    )


def _probe(prompt_tokens: int, estimated: int = 10_000, completion: int = 300) -> Measured:
    return Measured(prompt_tokens, estimated, completion, "x" * (completion * 4), 1.0)


def test_a_server_count_far_from_ours_is_not_trusted(window):
    """1 prompt token reported for a request of ten frames: the estimate keeps our count and
    says why, instead of turning a grid's cost into cents."""
    gemini = load_registry().get("gemini")
    ours = estimate_cost(gemini, window, episodes=240, max_steps=50, measured=_probe(10_000))
    for reported in (1, 10_000 // 5, 10_000 * 5):
        lying = estimate_cost(gemini, window, episodes=240, max_steps=50,
                              measured=_probe(reported))  # fmt: skip
        assert lying.prompt_tokens == ours.prompt_tokens and lying.basis == "registry"
        assert f"reported {reported:,} prompt tokens" in lying.warning
        assert "more than 4x apart" in lying.warning
    for reported in (10_000 // 4 + 1, 10_000 * 4):
        trusted = estimate_cost(gemini, window, episodes=240, max_steps=50,
                                measured=_probe(reported))  # fmt: skip
        assert trusted.warning is None and trusted.basis == "probe"


def test_a_distrusted_count_is_a_warning_in_the_preflight(json_server, monkeypatch):
    from pytest_emrd.preflight import preflight

    from .conftest import FakeVLLM

    fake = FakeVLLM()

    def one_token(method, path, body):
        status, payload = fake.answer(method, path, body)
        if method == "POST" and status == 200:
            payload["usage"]["prompt_tokens"] = 1
        return status, payload

    base_url = json_server(one_token)
    config = dataclasses.replace(load_registry().get("qwen3-vl-32b"), base_url=base_url,
                                 price_per_mtok_in=2.0, price_per_mtok_out=12.0)  # fmt: skip
    monkeypatch.delenv("VLLM_API_KEY", raising=False)
    report = preflight(config, SPEC, episodes=12)
    usage = next(c for c in report.checks if c.name == "usage")
    assert usage.status == "warn" and "reported 1 prompt tokens" in usage.detail
    assert report.failed is None and report.estimate.basis == "registry"
    assert report.estimate.prompt_tokens > 1_000_000


def test_completion_tokens_are_a_max_tokens_bound_next_to_the_expected(window):
    gemini = load_registry().get("gemini")
    estimate = estimate_cost(gemini, window, episodes=2, max_steps=50, measured=_probe(10_000))
    assert estimate.completion_tokens == 300 * 50 * 2
    assert estimate.completion_bound == gemini.max_tokens * 50 * 2 == 409_600
    assert estimate.cost_bound_usd > estimate.cost_usd
    line = estimate.line()
    assert "~30,000 completion tokens expected (<= 409,600 at max_tokens 4,096)" in line
    assert f"~${estimate.cost_usd:,.2f} expected, <= ${estimate.cost_bound_usd:,.2f}" in line
