"""Model registry: shipped entries (paper Appendix C), user overrides, parametric names, errors."""

from __future__ import annotations

from pathlib import Path

import pytest

from pytest_emrd.agent import REFERENCE_VERSION, ModelConfig, load_registry
from pytest_emrd.errors import ConfigError

PAPER_MODELS = [
    "gemini",
    "gpt",
    "claude",
    "qwen3-vl-32b",
    "ovis2-34b",
    "pixtral-12b",
    "internvl3-14b",
]


@pytest.mark.parametrize("name", PAPER_MODELS)
def test_paper_hyperparameters(name: str) -> None:
    config = load_registry().get(name)
    assert config.max_tokens == 4096
    assert config.modality == "vision"
    if name == "claude":  # "Default (1.0)": the provider default, so nothing is sent
        assert (config.temperature, config.single_image, config.provider) == (
            None,
            True,
            "anthropic",
        )
    else:
        assert (config.temperature, config.single_image, config.provider) == (0.0, False, "openai")
    assert config.base_url and config.base_url.startswith("http")


def test_reference_agents_and_parametric_names() -> None:
    registry = load_registry()
    assert registry.get("scout").modality == "both"
    assert registry.get("scout").base_url is None
    assert registry.get("scout-decay-8").planted == {
        "policy": "scout",
        "memory": "decay",
        "mean_steps": 8.0,
    }
    assert registry.get("scout-decay-2.5").planted["mean_steps"] == 2.5
    assert registry.get("scout-window-7").planted == {"policy": "scout", "memory": "window", "k": 7}
    assert registry.get("scout-serial").planted["memory"] == "serial"
    assert registry.get("prior").planted["policy"] == "prior"
    assert set(PAPER_MODELS) | {"scout", "scout-serial", "prior"} <= set(registry.names())


@pytest.mark.parametrize(
    "name", ["scout", "prior", "scout-serial", "scout-decay-8", "scout-window-5"]
)
def test_reference_model_ids_carry_the_behaviour_version(name: str) -> None:
    assert load_registry().get(name).model_id == f"{name}@{REFERENCE_VERSION}"


def test_user_reference_entry_is_versioned_once(tmp_path: Path) -> None:
    user = tmp_path / "models.yaml"
    user.write_text(
        "models:\n"
        "  mine: {provider: reference, model_id: 'scout@ref-0', planted: {policy: scout}}\n"
        "  gemini: {model_id: gemini-2.5-pro}\n"
    )
    registry = load_registry(user)
    assert registry.get("mine").model_id == f"scout@{REFERENCE_VERSION}"
    assert registry.get("gemini").model_id == "gemini-2.5-pro", "VLM ids are sent as written"


def test_base_url_env_override(monkeypatch) -> None:
    monkeypatch.setenv("EMRD_QWEN3_VL_32B_BASE_URL", "http://gpu-box:9000/v1")
    assert load_registry().get("qwen3-vl-32b").base_url == "http://gpu-box:9000/v1"
    monkeypatch.delenv("EMRD_QWEN3_VL_32B_BASE_URL")
    assert load_registry().get("qwen3-vl-32b").base_url == "http://localhost:8000/v1"


def test_user_file_overrides_fields_and_adds_models(tmp_path: Path) -> None:
    user = tmp_path / "models.yaml"
    user.write_text(
        "models:\n"
        "  qwen3-vl-32b: {base_url: 'http://10.0.0.5:8000/v1', single_image: true}\n"
        "  llava: {provider: openai, base_url: 'http://x/v1', model_id: llava-1.6,\n"
        "          modality: both}\n"
    )
    registry = load_registry(user)
    qwen = registry.get("qwen3-vl-32b")
    assert (qwen.base_url, qwen.single_image, qwen.model_id) == (
        "http://10.0.0.5:8000/v1",
        True,
        "Qwen/Qwen3-VL-32B-Instruct",
    )
    assert registry.get("llava") == ModelConfig(
        name="llava",
        provider="openai",
        base_url="http://x/v1",
        model_id="llava-1.6",
        modality="both",
    )


def test_unknown_model_lists_known_names() -> None:
    with pytest.raises(ConfigError) as info:
        load_registry().get("gpt-4o")
    message = str(info.value)
    assert "model='gpt-4o' is not in the registry" in message
    for name in PAPER_MODELS:
        assert name in message
    assert "scout-decay-<mean steps>" in message


@pytest.mark.parametrize(
    ("yaml_text", "match"),
    [
        ("models: [1, 2]", "top-level 'models:' mapping"),
        ("just text", "top-level 'models:' mapping"),
        (
            "models: {a: {provider: openai, model_id: m, base_url: 'http://x', temprature: 0}}",
            r"unknown field\(s\) \['temprature'\]",
        ),
        ("models: {a: {provider: azure, model_id: m, base_url: 'http://x'}}", "provider='azure'"),
        ("models: {a: {provider: openai, model_id: m}}", "base_url is required"),
        (
            "models: {a: {provider: openai, model_id: m, base_url: 'http://x', temperature: 3}}",
            r"temperature=3 must lie in \[0.0, 2.0\]",
        ),
        (
            "models: {a: {provider: openai, model_id: m, base_url: 'http://x', max_tokens: 0}}",
            "max_tokens=0 must be a whole number",
        ),
        (
            "models: {a: {provider: openai, model_id: m, base_url: 'http://x', modality: smell}}",
            "modality='smell'",
        ),
        ("models: {a: {provider: openai, base_url: 'http://x'}}", "model_id"),
        (
            "models: {a: {provider: openai, model_id: m, base_url: '${EMRD_UNSET_FOR_TEST}', "
            "env: [EMRD_UNSET_FOR_TEST]}}",
            "needs the environment variable EMRD_UNSET_FOR_TEST",
        ),
        (
            "models: {a: {provider: openai, model_id: m, base_url: 'http://x', planted: {k: 1}}}",
            "planted parameters are only for reference agents",
        ),
        (
            "models: {a: {provider: openai, model_id: m, base_url: 'http://x', max_retries: 1.5}}",
            "max_retries=1.5 must be a whole number",
        ),
        ("models: {a: 7}", "must be a mapping of fields"),
        ("models: {a: [unclosed", r"bad.yaml, line 1, column \d+: malformed YAML"),
    ],
    ids=[
        "models-not-mapping",
        "no-models-key",
        "typo-field",
        "bad-provider",
        "no-base-url",
        "temperature-range",
        "max-tokens",
        "bad-modality",
        "missing-model-id",
        "unset-env",
        "planted-on-vlm",
        "fractional-retries",
        "entry-not-mapping",
        "bad-yaml",
    ],
)
def test_bad_user_registry(tmp_path: Path, yaml_text: str, match: str) -> None:
    user = tmp_path / "bad.yaml"
    user.write_text(yaml_text)
    with pytest.raises(ConfigError, match=match):
        load_registry(user)


def test_missing_user_file(tmp_path: Path) -> None:
    with pytest.raises(ConfigError, match=r"nope\.yaml does not exist; pass an existing file"):
        load_registry(tmp_path / "nope.yaml")


@pytest.mark.parametrize(
    "name",
    ["scout-decay-0", "scout-decay-0.5", "scout-window-0"],
    ids=["decay-zero", "decay-below-one-step", "window-zero"],
)
def test_bad_parametric_names(name: str) -> None:
    with pytest.raises(ConfigError, match=name):
        load_registry().get(name)


_OPENAI = "provider: openai, model_id: m, base_url: 'http://x'"
_ANTHROPIC = "provider: anthropic, model_id: m, base_url: 'http://x'"


@pytest.mark.parametrize(
    ("fields", "match"),
    [
        (f"{_OPENAI}, temperature: hot", r"temperature='hot' must be a number in \[0.0, 2.0\]"),
        (f"{_OPENAI}, top_p: 1.5", r"top_p=1.5 must lie in \[0.0, 1.0\]"),
        (f"{_OPENAI}, max_tokens_param: max_output_tokens", "'max_tokens', 'max_completion"),
        (f"{_OPENAI}, api_key_required: maybe", "api_key_required='maybe' must be true or false"),
        (f"{_OPENAI}, extra_body: [1]", "extra_body must be a mapping of name -> value, got list"),
        (f"{_OPENAI}, extra_body: {{temperature: 0}}", "extra_body may not set 'temperature'"),
        (f"{_OPENAI}, extra_body: {{messages: []}}", "extra_body may not set 'messages'"),
        (
            f"{_OPENAI}, extra_body: {{reasoning_effort: extreme}}",
            "reasoning_effort='extreme' is not one of 'none', 'minimal', 'low'",
        ),
        (f"{_OPENAI}, extra_body: {{verbosity: loud}}", "verbosity='loud' is not one of 'low'"),
        (
            f"{_OPENAI}, extra_headers: {{Authorization: 'Bearer sk-x'}}",
            "extra_headers may not carry the credential header Authorization;.*api_key_env",
        ),
        (
            f"{_OPENAI}, extra_headers: {{X-Trace: 7}}",
            "extra_headers.X-Trace must be a string, got int; quote",
        ),
        (
            f"{_ANTHROPIC}, temperature: 1.0",
            r"temperature=1.0 is rejected by the Anthropic Messages API version 2026-10-21; "
            r"allowed: null \(provider default\), or pin extra_headers",
        ),
        (f"{_ANTHROPIC}, top_p: 0.9", "top_p=0.9 is rejected by the Anthropic Messages API"),
        (
            f"{_ANTHROPIC}, temperature: 1.5, extra_headers: {{anthropic-version: '2023-06-01'}}",
            r"temperature=1.5 must lie in \[0.0, 1.0\]",
        ),
    ],
    ids=[
        "temperature-not-number",
        "top-p-range",
        "max-tokens-param",
        "key-required-not-bool",
        "extra-body-not-mapping",
        "extra-body-owns-temperature",
        "extra-body-owns-messages",
        "reasoning-effort",
        "verbosity",
        "credential-header",
        "header-not-string",
        "anthropic-temperature",
        "anthropic-top-p",
        "anthropic-legacy-range",
    ],
)
def test_bad_provider_fields_name_file_field_and_allowed_values(
    tmp_path: Path, fields: str, match: str
) -> None:
    user = tmp_path / "bad.yaml"
    user.write_text(f"models: {{a: {{{fields}}}}}")
    with pytest.raises(ConfigError, match=match) as info:
        load_registry(user)
    message = str(info.value)
    assert message.startswith(f"{user}, line 1: model 'a': ") and "\n" not in message


@pytest.mark.parametrize(
    ("entry", "line", "match"),
    [
        ("    temperature: 3\n", 6, r"temperature=3 must lie in \[0.0, 2.0\]"),
        ("    extra_headers: {x-trace: 7}\n", 6, "extra_headers.x-trace must be a string, got int"),
        ("    temprature: 0.2\n", 6, "unknown field"),
        ("    max_retries: 1\n", 3, "base_url is required"),
    ],
    ids=["field-range", "header-value", "typo-field", "missing-field-names-the-model"],
)
def test_registry_errors_name_the_line_of_the_field(
    tmp_path: Path, entry: str, line: int, match: str
) -> None:
    user = tmp_path / "models.yaml"
    user.write_text(
        "# my models\nmodels:\n  mine:\n    provider: openai\n    model_id: m\n"
        + entry
        + ("    base_url: 'http://x'\n" if "base_url" not in match else "")
    )
    with pytest.raises(ConfigError, match=match) as info:
        load_registry(user)
    assert str(info.value).startswith(f"{user}, line {line}: ")


def test_optional_fields_load(tmp_path: Path) -> None:
    user = tmp_path / "models.yaml"
    user.write_text(
        "models:\n"
        "  mine: {provider: openai, model_id: m, base_url: 'http://x', temperature: null,\n"
        "         top_p: 0.9, extra_body: {reasoning_effort: low, seed: 7},\n"
        "         extra_headers: {X-Trace: abc}}\n"
        "  legacy: {provider: anthropic, model_id: c, base_url: 'http://x', temperature: 0.5,\n"
        "           extra_headers: {anthropic-version: '2023-06-01'}}\n"
        "  claude: {model_id: claude-next}\n"
    )
    registry = load_registry(user)
    mine = registry.get("mine")
    assert (mine.temperature, mine.top_p) == (None, 0.9)
    assert mine.extra_body == {"reasoning_effort": "low", "seed": 7}
    assert mine.extra_headers == {"X-Trace": "abc"}
    assert registry.get("legacy").temperature == 0.5
    assert registry.get("claude").temperature is None, "a user override keeps the shipped null"


def test_new_anthropic_entry_defaults_to_the_provider_temperature(tmp_path: Path) -> None:
    user = tmp_path / "models.yaml"
    user.write_text("models: {sonnet: {provider: anthropic, model_id: s, base_url: 'http://x'}}")
    assert load_registry(user).get("sonnet").temperature is None


def test_shipped_api_models_carry_their_provider_requirements() -> None:
    registry = load_registry()
    assert registry.get("gpt").extra_body == {"reasoning_effort": "none"}
    for name in ("qwen3-vl-32b", "ovis2-34b", "pixtral-12b", "internvl3-14b"):
        config = registry.get(name)
        assert (config.api_key_env, config.api_key_required) == ("VLLM_API_KEY", False)
