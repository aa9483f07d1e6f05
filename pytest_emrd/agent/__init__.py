"""Agent stage: prompts, reply protocol, history window, model clients and registry.

The built-in scripted agents live in :mod:`pytest_emrd.agent.reference`.
"""

from pytest_emrd.agent._clients import (
    AnthropicClient,
    ChatClient,
    ChatResponse,
    OpenAICompatibleClient,
    ProviderRequest,
    build_request,
    make_client,
)
from pytest_emrd.agent._config import (
    ANTHROPIC_VERSION,
    PROVIDERS,
    ModelConfig,
    Registry,
    load_registry,
)
from pytest_emrd.agent._history import HISTORY_TURNS, Conversation, UserTurn
from pytest_emrd.agent._parse import REPAIRS, Reply, parse_reply
from pytest_emrd.agent._prompt import (
    NEUTRAL_NAMES,
    PROMPT_VERSION,
    ROOM_SUFFIXES,
    build_system_prompt,
    resolve_room,
    room_aliases,
    step_text,
)
from pytest_emrd.agent._retry import RetryPolicy
from pytest_emrd.agent._vllm import serve_command

__all__ = [
    "ANTHROPIC_VERSION",
    "HISTORY_TURNS",
    "NEUTRAL_NAMES",
    "PROMPT_VERSION",
    "PROVIDERS",
    "REPAIRS",
    "ROOM_SUFFIXES",
    "AnthropicClient",
    "ChatClient",
    "ChatResponse",
    "Conversation",
    "ModelConfig",
    "OpenAICompatibleClient",
    "ProviderRequest",
    "Registry",
    "Reply",
    "RetryPolicy",
    "UserTurn",
    "build_request",
    "build_system_prompt",
    "load_registry",
    "make_client",
    "parse_reply",
    "resolve_room",
    "room_aliases",
    "serve_command",
    "step_text",
]
