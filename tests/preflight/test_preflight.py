"""Preflight against real HTTP servers on 127.0.0.1: the reference server and a vLLM-like
server that refuses with vLLM's own sentences."""

from __future__ import annotations

import base64
import io
import json
import shlex

import pytest
from PIL import Image

from pytest_emrd.agent import load_registry
from pytest_emrd.cli import main
from pytest_emrd.preflight import preflight
from pytest_emrd.trajectory import EpisodeSpec

from .conftest import CONTEXT_MESSAGES, FakeVLLM


def _spec(model: str, modality: str = "vision") -> EpisodeSpec:
    return EpisodeSpec(model, "baseline", "office", 0, modality=modality)


def _status(report) -> dict[str, str]:
    return {c.name: c.status for c in report.checks}


def test_the_reference_agent_passes_with_a_full_window_of_real_frames():
    config = load_registry().get("scout")
    report = preflight(config, _spec("scout", "both"), episodes=240)
    assert report.failed is None, report.lines()
    assert _status(report) == {
        "key": "pass",
        "url": "pass",
        "probe": "pass",
        "images": "pass",
        "context": "info",
        "estimate": "info",
    }
    assert "took 10 frames in one request" in report.lines()[4]
    assert report.estimate is not None and report.estimate.basis == "probe"
    assert report.estimate.episodes == 240 and report.estimate.cost_usd is None


def test_the_probe_carries_real_512_frames_and_parses_the_reply(fake_vllm, registry_for):
    registry = load_registry(registry_for(fake_vllm.base_url))
    report = preflight(registry.get("qwen3-vl-32b"), _spec("qwen3-vl-32b"), episodes=12)
    assert report.failed is None, report.lines()
    (body,) = fake_vllm.requests
    assert body["model"] == "Qwen/Qwen3-VL-32B-Instruct" and body["max_tokens"] == 4096
    urls = [
        p["image_url"]["url"]
        for m in body["messages"]
        if isinstance(m["content"], list)
        for p in m["content"]
        if p["type"] == "image_url"
    ]
    assert len(urls) == 10, "as many frames as the history window sends"
    sizes = {Image.open(io.BytesIO(base64.b64decode(u.split(",", 1)[1]))).size for u in urls}
    assert sizes == {(512, 512)}
    assert len(set(urls)) == 4, "a real sweep: four headings, turning right every step"
    assert [m["role"] for m in body["messages"]][:3] == ["system", "user", "assistant"]
    checks = {c.name: c for c in report.checks}
    assert checks["context"].status == "pass" and "40,960" in checks["context"].detail
    assert report.estimate.basis == "probe" and report.estimate.cost_usd is None


def test_too_few_images_names_the_limit_flag(fake_vllm, registry_for):
    fake_vllm.image_limit = 1
    registry = load_registry(registry_for(fake_vllm.base_url))
    report = preflight(registry.get("qwen3-vl-32b"), _spec("qwen3-vl-32b"), episodes=12)
    assert _status(report)["images"] == "fail"
    message = report.message()
    assert "'qwen3-vl-32b'" in message and "'probe'" in message
    assert "--limit-mm-per-prompt '{\"image\": 10}'" in message
    assert "At most 1 image(s) may be provided in one prompt." in message
    assert report.estimate.basis == "registry", "no answer: the registry's figures"


@pytest.mark.parametrize("wording", sorted(CONTEXT_MESSAGES))
def test_a_short_context_names_max_model_len(fake_vllm, registry_for, wording):
    fake_vllm.max_model_len, fake_vllm.context_message = 8192, wording
    registry = load_registry(registry_for(fake_vllm.base_url))
    report = preflight(registry.get("qwen3-vl-32b"), _spec("qwen3-vl-32b"), episodes=12)
    context = next(c for c in report.checks if c.name == "context")
    assert context.status == "fail"
    assert "--max-model-len 16384" in context.fix, context.fix
    assert "8,192" in context.fix


def test_a_server_serving_another_model_names_served_model_name(fake_vllm, registry_for):
    fake_vllm.model_id = "Qwen/Qwen2.5-VL-7B-Instruct"
    registry = load_registry(registry_for(fake_vllm.base_url))
    report = preflight(registry.get("qwen3-vl-32b"), _spec("qwen3-vl-32b"), episodes=12)
    assert _status(report)["url"] == "fail" and _status(report)["probe"] == "skip"
    assert "--served-model-name Qwen/Qwen3-VL-32B-Instruct" in report.message()
    assert fake_vllm.requests == [], "nothing is sent to the wrong model"


def test_a_down_server_fails_fast_without_a_probe(registry_for, unused_port):
    registry = load_registry(registry_for(f"http://127.0.0.1:{unused_port}/v1"))
    report = preflight(registry.get("qwen3-vl-32b"), _spec("qwen3-vl-32b"), episodes=12)
    assert _status(report)["url"] == "fail" and _status(report)["probe"] == "skip"
    assert "start the server" in report.failed.fix


def test_a_down_server_of_ones_own_model_names_its_registry_not_ours(tmp_path, unused_port):
    path = tmp_path / "models.yaml"
    url = f"http://127.0.0.1:{unused_port}/v1"
    entry = {
        "provider": "openai",
        "model_id": "org/mine",
        "api_key_required": False,
        "base_url": url,
    }
    path.write_text(json.dumps({"models": {"my-vlm": entry}}), encoding="utf-8")
    report = preflight(load_registry(path).get("my-vlm"), _spec("my-vlm"), episodes=1)
    fix = report.failed.fix
    assert "model_id='org/mine'" in fix and "base_url of 'my-vlm' in your registry" in fix
    assert "EMRD_" not in fix and "vllm.md" not in fix


def test_a_missing_key_is_named_and_nothing_is_sent(fake_vllm, registry_for, monkeypatch):
    monkeypatch.delenv("EMRD_TEST_VLM_KEY", raising=False)
    path = registry_for(fake_vllm.base_url, api_key_env="EMRD_TEST_VLM_KEY", api_key_required=True)
    report = preflight(load_registry(path).get("qwen3-vl-32b"), _spec("qwen3-vl-32b"), episodes=1)
    assert report.failed.name == "key" and "EMRD_TEST_VLM_KEY is not set" in report.message()
    assert fake_vllm.requests == []


def test_an_optional_key_may_be_unset(fake_vllm, registry_for, monkeypatch):
    """The open models send VLLM_API_KEY only when it is set (a server without --api-key)."""
    monkeypatch.delenv("VLLM_API_KEY", raising=False)
    report = preflight(
        load_registry(registry_for(fake_vllm.base_url)).get("qwen3-vl-32b"),
        _spec("qwen3-vl-32b"),
        episodes=1,
    )
    key = next(check for check in report.checks if check.name == "key")
    assert (key.status, key.detail) == ("pass", "VLLM_API_KEY is not set: no key is sent")


def test_single_image_and_text_modality_send_one_and_no_frame(fake_vllm, registry_for):
    fake_vllm.image_limit = 1
    path = registry_for(fake_vllm.base_url, single_image=True)
    report = preflight(load_registry(path).get("qwen3-vl-32b"), _spec("qwen3-vl-32b"), episodes=1)
    assert report.failed is None and "took 1 frames" in report.lines()[4]
    report = preflight(
        load_registry(path).get("qwen3-vl-32b"), _spec("qwen3-vl-32b", "text"), episodes=1
    )
    assert report.failed is None and _status(report)["images"] == "info"


def test_emrd_check_exits_1_and_names_the_flag(fake_vllm, registry_for, capsys):
    fake_vllm.image_limit = 4
    path = registry_for(fake_vllm.base_url)
    argv = ["check", "--emrd-model=qwen3-vl-32b", f"--emrd-models={path}", "--emrd-episodes=1"]
    assert main(argv) == 1
    out = capsys.readouterr().out
    assert "FAIL  images" in out and "--limit-mm-per-prompt" in out
    assert "12 episodes x <= 50 steps" in out, "3 conditions x 4 spawns x 1 episode"
    fake_vllm.image_limit = 10
    assert main([*argv, "--json"]) == 0
    (report,) = json.loads(capsys.readouterr().out)
    assert report["model"] == "qwen3-vl-32b" and report["estimate"]["episodes"] == 12


@pytest.mark.parametrize("key", [None, "wrong-key"], ids=["no-key", "refused-key"])
def test_a_401_listing_fails_the_url_check(json_server, registry_for, monkeypatch, key):
    """An endpoint that refuses us is up but not usable: the url check fails, never passes."""
    fake = FakeVLLM()
    seen: list[dict[str, str]] = []

    def locked(method, path, body):
        if method == "GET":
            return 401, {"error": {"message": "invalid api key"}}
        return fake.answer(method, path, body)

    base_url = json_server(locked)
    if key is None:
        monkeypatch.delenv("EMRD_TEST_VLM_KEY", raising=False)
    else:
        monkeypatch.setenv("EMRD_TEST_VLM_KEY", key)
    path = registry_for(base_url, api_key_env="EMRD_TEST_VLM_KEY", api_key_required=False)
    report = preflight(load_registry(path).get("qwen3-vl-32b"), _spec("qwen3-vl-32b"), episodes=1)
    assert _status(report)["url"] == "fail" and _status(report)["probe"] == "skip"
    url = next(c for c in report.checks if c.name == "url")
    assert "answered HTTP 401" in url.detail
    if key is None:
        assert "wants a key and none was sent" in url.detail
        assert url.fix == "export EMRD_TEST_VLM_KEY=<your key>"
    else:
        assert "the key in EMRD_TEST_VLM_KEY was refused" in url.detail
    assert fake.requests == [] and not seen


def test_the_check_again_command_names_the_registry(fake_vllm, registry_for, capsys):
    fake_vllm.image_limit = 1
    path = registry_for(fake_vllm.base_url)
    config = load_registry(path).get("qwen3-vl-32b")
    report = preflight(config, _spec("qwen3-vl-32b"), episodes=1, models_file=str(path))
    assert report.message().endswith(
        f"Check again with: emrd check --emrd-model=qwen3-vl-32b --emrd-models={path}"
    )
    # run as printed: it finds the model (exit 1, the same refusal), not a usage error (2)
    program, *argv = shlex.split(report.check_command)
    assert program == "emrd" and main([*argv, "--no-probe"]) == 0
    assert main(argv) == 1 and "FAIL  images" in capsys.readouterr().out
