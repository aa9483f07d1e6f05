"""Agent stage: prompts, reply protocol, history window, model clients and registry.

The built-in scripted agents live in :mod:`pytest_emrd.reference` (their behaviour version,
which the registry writes into their model ids, lives here). Names are imported
on first use (:mod:`pytest_emrd._lazy`): reading the model registry does not import the HTTP
clients (httpx) or the reference agents.
"""

from pytest_emrd._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(
    __name__,
    {
        "_clients": (
            "AnthropicClient",
            "ChatClient",
            "ChatResponse",
            "OpenAICompatibleClient",
            "ProviderRequest",
            "build_request",
            "endpoint_url",
            "make_client",
        ),
        "_config": ("ANTHROPIC_VERSION", "PROVIDERS", "ModelConfig", "Registry", "load_registry"),
        "_history": ("HISTORY_TURNS", "JPEG_DATA_URL", "Conversation", "UserTurn"),
        "_parse": ("MAX_REPLY_CHARS", "REPAIRS", "Reply", "parse_reply"),
        "_prompt": (
            "NEUTRAL_NAMES",
            "OVERVIEW_HEADING",
            "PROMPT_VERSION",
            "ROOM_SUFFIXES",
            "VISIBLE_HEADING",
            "build_system_prompt",
            "read_profile",
            "resolve_room",
            "room_aliases",
            "step_text",
        ),
        "_retry": ("RetryPolicy",),
        "_version": ("REFERENCE_VERSION", "agent_name", "versioned_id"),
        "_vllm": ("serve_command",),
    },
)
