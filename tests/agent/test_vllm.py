"""vLLM serving: the README's commands come from the code; refusals map to the missing flag."""

from __future__ import annotations

import re
from pathlib import Path

import pytest

from pytest_emrd.agent import HISTORY_TURNS, load_registry, serve_command, vllm_fix
from pytest_emrd.agent._vllm import MAX_MODEL_LEN

OPEN_MODELS = ["qwen3-vl-32b", "ovis2-34b", "pixtral-12b", "internvl3-14b"]
README = Path(__file__).parents[2] / "README.md"


@pytest.mark.parametrize("name", OPEN_MODELS)
def test_readme_shows_the_exact_serve_command(name: str) -> None:
    command = serve_command(load_registry().get(name))
    assert command in README.read_text()
    assert f"'{{\"image\": {HISTORY_TURNS}}}'" in command
    assert f"--max-model-len {MAX_MODEL_LEN}" in command


def test_serve_command_is_only_for_the_shipped_open_models() -> None:
    with pytest.raises(KeyError):
        serve_command(load_registry().get("gpt"))


@pytest.mark.parametrize(
    ("status", "body", "problem", "flag", "hint"),
    [
        (
            400,
            '{"error": {"message": "At most 8 image(s) may be provided in one prompt. Set '
            '`--limit-mm-per-prompt` to increase this limit. (parameter=image)"}}',
            "image_limit",
            "--limit-mm-per-prompt",
            r"accepts 8 image\(s\) per prompt .* --limit-mm-per-prompt '\{\"image\": 10\}'",
        ),
        (
            400,
            "This model's maximum context length is 8192 tokens. However, you requested 21000 "
            "tokens (16904 in the messages, 4096 in the completion).",
            "context_length",
            "--max-model-len",
            "context is 8192 tokens .* --max-model-len 32768",
        ),
        (
            400,
            "The decoder prompt (length 17772) is longer than the maximum model length of 16384.",
            "context_length",
            "--max-model-len",
            "context is 16384 tokens",
        ),
        (
            400,
            "The prompt (total length 25938) is too long to fit into the model (context length "
            "4096). Make sure that `max_model_len` is no smaller than the number of text tokens "
            "plus multimodal tokens.",
            "context_length",
            "--max-model-len",
            "context is 4096 tokens",
        ),
        (401, '{"error": "Unauthorized"}', "unauthorized", "api_key_env", "VLLM_API_KEY"),
        (
            404,
            '{"object": "error", "message": "The model `Qwen/Qwen3-VL-32B-Instruct` does not '
            'exist.", "type": "NotFoundError", "code": 404}',
            "unknown_model",
            "--served-model-name",
            "does not serve 'Qwen/Qwen3-VL-32B-Instruct'",
        ),
    ],
    ids=["image-limit", "context-openai-wording", "decoder-prompt", "mm-prompt", "401", "404"],
)
def test_refusals_name_the_flag(status, body, problem, flag, hint) -> None:
    fix = vllm_fix(status, body, model_id="Qwen/Qwen3-VL-32B-Instruct")
    assert fix is not None and (fix.problem, fix.flag) == (problem, flag)
    assert re.search(hint, fix.hint), fix.hint


@pytest.mark.parametrize(
    ("status", "body"),
    [(500, "Internal Server Error"), (400, '{"error": "temperature must be >= 0"}')],
    ids=["server-error", "other-bad-request"],
)
def test_unknown_refusals_give_none(status: int, body: str) -> None:
    assert vllm_fix(status, body) is None
