"""Preflight: before a live grid spends money or hours, check the model can run it.

:func:`preflight` checks one model (key, endpoint, a real probe request, context, image
limit) and estimates its live episodes' tokens and cost; ``emrd check`` runs it, and the
plugin runs it once per model before any episode is recorded.
"""

from pytest_emrd._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(
    __name__,
    {
        "_check": ("Check", "PreflightReport", "preflight"),
        "_estimate": (
            "DEFAULT_COMPLETION_TOKENS",
            "CostEstimate",
            "Measured",
            "Sweep",
            "count_images",
            "request_tokens",
            "sample_reply",
            "sweep",
        ),
        "_server": ("Refusal", "ServerInfo", "models_url", "server_info", "vllm_refusal"),
        "_session": ("SessionPreflight", "live_grid", "params_of_node_ids", "preflight_live"),
    },
)
