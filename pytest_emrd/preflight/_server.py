"""What the endpoint says: ``GET /models`` (reachability, served ids, context), and vLLM's
refusals read back into the ``vllm serve`` flag that prevents them.

The listing is asked for with the model's key and headers, as the probe will be: HTTP 401 or
403 means the endpoint refuses us, a failure (:attr:`ServerInfo.refused`), never a pass.
vLLM lists each served model with ``max_model_len``. The refusal texts are vLLM's own
(``validate_num_items``, ``_token_len_check``, the "decoder prompt" and older "maximum context
length" messages); each names the number the fix needs.
"""

from __future__ import annotations

import json
import re
from dataclasses import dataclass
from typing import Final

import httpx

#: Seconds to wait for ``GET /models``: a local server answers at once, a missing one fails.
LIST_TIMEOUT_S: Final = 10.0


@dataclass(frozen=True)
class ServerInfo:
    """The answer to ``GET /models`` (or why there was none)."""

    url: str
    status: int | None
    """HTTP status, ``None`` when the server could not be reached."""
    served: tuple[str, ...] = ()
    """Model ids the listing names (empty when it could not be read)."""
    max_model_len: int | None = None
    """Context length the server reports for our model (vLLM), else ``None``."""
    error: str | None = None
    """Transport error when unreachable."""

    @property
    def reachable(self) -> bool:
        return self.status is not None

    @property
    def refused(self) -> bool:
        """The server answered that our credentials are missing or wrong (401, 403)."""
        return self.status in (401, 403)

    def serves(self, model_id: str) -> bool | None:
        """Whether the listing names ``model_id`` (``models/`` prefixes ignored); ``None``
        when there is no readable listing."""
        if not self.served:
            return None
        return model_id in {s.removeprefix("models/") for s in self.served}


def models_url(provider: str, base_url: str) -> str:
    """The model listing of an endpoint (Anthropic's lives under ``/v1``), joined as the
    clients join their endpoints: after the base path, the base query kept.

    :param provider: The provider's name (``openai``, ``anthropic``, ...).
    :param base_url: The endpoint's base URL.
    :returns: The listing's URL.
    """
    from pytest_emrd.agent import endpoint_url

    return endpoint_url(base_url, "/v1/models" if provider == "anthropic" else "/models")


def server_info(url: str, model_id: str, *, headers: dict[str, str] | None = None) -> ServerInfo:
    """``GET url`` with ``headers`` (the key, when there is one); never raises for a network
    or protocol failure.

    :param url: The model listing's URL (:func:`models_url`).
    :param model_id: The model whose entry is looked for.
    :param headers: Request headers, the key included.
    :returns: The :class:`ServerInfo`: what the server said, or the failure.
    """
    try:
        response = httpx.get(url, timeout=LIST_TIMEOUT_S, headers=headers)
    except httpx.HTTPError as exc:
        return ServerInfo(url, None, error=f"{type(exc).__name__}: {exc}")
    if response.status_code != 200:
        return ServerInfo(url, response.status_code)
    try:
        data = response.json()
    except ValueError:
        return ServerInfo(url, 200)
    items = data.get("data") if isinstance(data, dict) else None
    entries = [i for i in items if isinstance(i, dict)] if isinstance(items, list) else []
    served = tuple(str(e.get("id")) for e in entries if e.get("id"))
    ours = next((e for e in entries if str(e.get("id")).removeprefix("models/") == model_id), {})
    length = ours.get("max_model_len")
    return ServerInfo(
        url,
        200,
        served=served,
        max_model_len=length if type(length) is int else None,  # not a bool either
    )


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


def _first(patterns: tuple[re.Pattern[str], ...], text: str) -> int | None:
    """The number the first matching pattern captures (each captures one)."""
    for pattern in patterns:
        if match := pattern.search(text):
            return int(match[1])
    return None


def vllm_refusal(
    message: str, *, images: int, max_tokens: int, prompt_tokens: int
) -> Refusal | None:
    """The refusal in ``message`` (an HTTP error text), or ``None`` when it is not one of vLLM's.

    ``images`` is how many frames the window sends; ``max_tokens`` the completion budget;
    ``prompt_tokens`` our estimate of the largest request, used when vLLM does not say.

    :param message: The HTTP error text.
    :param images: Frames per request.
    :param max_tokens: The completion budget.
    :param prompt_tokens: Our estimate of the largest prompt.
    :returns: The :class:`Refusal` with its fix, or None.
    """
    if match := _IMAGES.search(message):
        limit = json.dumps({"image": images})
        return Refusal(
            "images",
            match[0] + ".",
            f"restart vLLM with --limit-mm-per-prompt '{limit}' (the window sends {images} "
            f"frames; this server takes {match['limit']})",
        )
    context = _first(_CONTEXT, message)
    if context is None:
        return None
    prompt = _first(_PROMPT, message) or prompt_tokens
    return Refusal(
        "context",
        f"maximum context length {context} tokens",
        context_fix(prompt, max_tokens, context),
    )


def context_fix(prompt: int, max_tokens: int, context: int) -> str:
    """The ``vllm serve`` flag that makes a ``context``-token server hold the window.

    :param prompt: Prompt tokens of the largest request.
    :param max_tokens: The completion budget.
    :param context: The server's context length.
    :returns: The fix, in words.
    """
    power = 1 << max(prompt + max_tokens - 1, 1).bit_length()  # the power of 2 >= their sum
    return (
        f"restart vLLM with --max-model-len {power} (a full window is "
        f"~{prompt:,} prompt tokens plus max_tokens={max_tokens}; this server holds {context:,})"
    )
