"""vLLM serving: the docs' commands come from the code."""

from __future__ import annotations

from pathlib import Path

import pytest

from pytest_emrd.agent import HISTORY_TURNS, load_registry, serve_command
from pytest_emrd.agent._vllm import MAX_MODEL_LEN

OPEN_MODELS = ["qwen3-vl-32b", "ovis2-34b", "pixtral-12b", "internvl3-14b"]
VLLM_PAGE = Path(__file__).parents[2] / "docs" / "user-guide" / "vllm.md"


@pytest.mark.parametrize("name", OPEN_MODELS)
def test_the_docs_show_the_exact_serve_command(name: str) -> None:
    command = serve_command(load_registry().get(name))
    assert command in VLLM_PAGE.read_text()
    assert f"'{{\"image\": {HISTORY_TURNS}}}'" in command
    assert f"--max-model-len {MAX_MODEL_LEN}" in command


def test_serve_command_is_only_for_the_shipped_open_models() -> None:
    with pytest.raises(KeyError):
        serve_command(load_registry().get("gpt"))
