"""Preflight: before a live grid spends money or hours, check the model can run it.

:func:`preflight` checks one model (key, endpoint, a real probe request, context, image
limit) and estimates its live episodes' tokens and cost; ``emrd check`` runs it, and the
plugin runs it once per model before any episode is recorded.
"""

from pytest_emrd.preflight._check import Check, PreflightReport, preflight
from pytest_emrd.preflight._estimate import (
    DEFAULT_COMPLETION_TOKENS,
    CostEstimate,
    Measured,
    Sweep,
    count_images,
    request_tokens,
    sample_reply,
    sweep,
)
from pytest_emrd.preflight._server import (
    Refusal,
    ServerInfo,
    models_url,
    server_info,
    vllm_refusal,
)
from pytest_emrd.preflight._session import (
    SessionPreflight,
    live_grid,
    params_of_node_ids,
    preflight_live,
)

__all__ = [
    "DEFAULT_COMPLETION_TOKENS",
    "Check",
    "CostEstimate",
    "Measured",
    "PreflightReport",
    "Refusal",
    "ServerInfo",
    "SessionPreflight",
    "Sweep",
    "count_images",
    "live_grid",
    "models_url",
    "params_of_node_ids",
    "preflight",
    "preflight_live",
    "request_tokens",
    "sample_reply",
    "server_info",
    "sweep",
    "vllm_refusal",
]
