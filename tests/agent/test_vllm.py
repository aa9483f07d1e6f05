"""vLLM serving: the docs' commands come from the code."""

from __future__ import annotations

from pathlib import Path

import pytest

from pytest_emrd.agent import HISTORY_TURNS, load_registry, serve_command
from pytest_emrd.agent._vllm import SERVED

OPEN_MODELS = ["qwen3-vl-32b", "ovis2-34b", "pixtral-12b", "internvl3-14b"]
VLLM_PAGE = Path(__file__).parents[2] / "docs" / "user-guide" / "vllm.md"


@pytest.mark.parametrize("name", OPEN_MODELS)
def test_the_docs_show_the_exact_serve_command(name: str) -> None:
    command = serve_command(load_registry().get(name))
    assert command in VLLM_PAGE.read_text()
    assert f"'{{\"image\": {HISTORY_TURNS}}}'" in command
    context = SERVED[load_registry().get(name).model_id][0]
    assert (f"--max-model-len {context}" in command) == (context is not None)
    assert "--dtype bfloat16" in command


def test_serve_commands_use_the_papers_context_and_parallelism() -> None:
    commands = {name: serve_command(load_registry().get(name)) for name in OPEN_MODELS}
    assert "--max-model-len 16384" in commands["qwen3-vl-32b"]
    assert "--max-model-len 24576" in commands["ovis2-34b"]
    assert "--max-model-len 16384" in commands["pixtral-12b"]
    assert "--max-model-len" not in commands["internvl3-14b"]  # the model's default
    assert all("--tensor-parallel-size 4" in commands[n] for n in OPEN_MODELS[:3])


def test_serve_command_is_only_for_the_shipped_open_models() -> None:
    with pytest.raises(KeyError):
        serve_command(load_registry().get("gpt"))
