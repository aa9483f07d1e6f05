"""Serving the open models with vLLM: the ``vllm serve`` command of each shipped open model.

:func:`serve_command` gives the command (``docs/user-guide/vllm.md`` shows the same strings; a
test keeps them equal, and the page says why each number is what it is). Reading a server's
refusal back into the missing flag is preflight's job (:func:`pytest_emrd.preflight.vllm_refusal`).
Flag syntax is vLLM >= 0.11.0 (the first release with Qwen3-VL): ``--limit-mm-per-prompt``
takes JSON since 0.10.0 (the older ``image=10`` form is refused, vllm-project/vllm#21615).
"""

from __future__ import annotations

from typing import Final

from pytest_emrd.agent._config import ModelConfig
from pytest_emrd.agent._history import HISTORY_TURNS

SERVED: Final[dict[str, tuple[int | None, int, tuple[str, ...]]]] = {
    "Qwen/Qwen3-VL-32B-Instruct": (16384, 4, ()),
    "AIDC-AI/Ovis2-34B": (24576, 4, ("--trust-remote-code",)),
    "mistralai/Pixtral-12B-2409": (
        16384,
        4,
        ("--tokenizer-mode mistral", "--config-format mistral", "--load-format mistral"),
    ),
    "OpenGVLab/InternVL3-14B": (None, 1, ("--trust-remote-code",)),
}
"""Per model, as the paper served it (Appendix C): ``--max-model-len`` (None: the model's
default), GPUs, and flags (``trust_remote_code`` as in vLLM's multi-image example; Pixtral's
``mistral`` formats as in Mistral's vLLM guide)."""
IMAGE_LIMIT_FLAG: Final = f"--limit-mm-per-prompt '{{\"image\": {HISTORY_TURNS}}}'"


def serve_command(config: ModelConfig, *, port: int = 8000) -> str:
    """The ``vllm serve`` command for a shipped open model (``KeyError`` for any other).

    :param config: A shipped open model's registry entry.
    :param port: The port the server listens on.
    :returns: The shell command line.
    """
    context, gpus, model_flags = SERVED[config.model_id]
    flags = (
        *model_flags,
        "--dtype bfloat16",
        f"--tensor-parallel-size {gpus}",
        IMAGE_LIMIT_FLAG,
        *(() if context is None else (f"--max-model-len {context}",)),
        f"--port {port}",
    )
    return " \\\n    ".join((f"vllm serve {config.model_id}", *flags))
