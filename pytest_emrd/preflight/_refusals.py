"""vLLM's refusals, read back into the ``vllm serve`` flag that prevents them.

The texts are vLLM's own (``vllm/multimodal/processing.py`` ``validate_num_items``;
``vllm/renderers/params.py`` ``_token_len_check``; the engine's "decoder prompt" check;
the older serving layer's "maximum context length" message); each names the number the
fix needs.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from typing import Final

_IMAGES: Final = re.compile(
    r"At most (?P<limit>\d+) image\(s\) may be provided in one (?:prompt|request)"
)
_CONTEXT: Final = (
    re.compile(r"maximum context length is (?P<context>\d+) tokens"),
    re.compile(r"context length is only (?P<context>\d+) tokens"),
    re.compile(r"longer than the maximum model length of (?P<context>\d+)"),
)
_PROMPT: Final = (
    re.compile(r"prompt contains (?:at least )?(?P<prompt>\d+) input tokens"),
    re.compile(r"You passed (?P<prompt>\d+) input tokens"),
    re.compile(r"prompt \(length (?P<prompt>\d+)\)"),
    re.compile(r"\((?P<prompt>\d+) in the messages"),
)


@dataclass(frozen=True)
class Refusal:
    """A refusal vLLM explains, and the flag that prevents it."""

    check: str
    """``images`` or ``context``."""
    said: str
    """The server's own sentence."""
    fix: str
    """What to restart the server with."""


def _first(patterns: tuple[re.Pattern[str], ...], text: str, group: str) -> int | None:
    for pattern in patterns:
        if match := pattern.search(text):
            return int(match[group])
    return None


def _power_of_two_at_least(n: int) -> int:
    return 1 << max(n - 1, 1).bit_length()


def vllm_refusal(
    message: str, *, images: int, max_tokens: int, prompt_tokens: int
) -> Refusal | None:
    """The refusal in ``message`` (an HTTP error text), or ``None`` when it is not one of vLLM's.

    ``images`` is how many frames the window sends; ``max_tokens`` the completion budget;
    ``prompt_tokens`` our estimate of the largest request, used when vLLM does not say.
    """
    if match := _IMAGES.search(message):
        limit = json.dumps({"image": images})
        return Refusal(
            "images",
            match[0] + ".",
            f"restart vLLM with --limit-mm-per-prompt '{limit}' (the window sends {images} "
            f"frames; this server takes {match['limit']})",
        )
    context = _first(_CONTEXT, message, "context")
    if context is None:
        return None
    prompt = _first(_PROMPT, message, "prompt") or prompt_tokens
    needed = prompt + max_tokens
    return Refusal(
        "context",
        f"maximum context length {context} tokens",
        f"restart vLLM with --max-model-len {_power_of_two_at_least(needed)} (a full window is "
        f"~{prompt:,} prompt tokens plus max_tokens={max_tokens}; this server holds {context:,})",
    )
