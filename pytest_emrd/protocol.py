"""The protocol version: what cassettes and stored results are keyed by.

Its own light module: every pytest process reads it, few need what
:mod:`pytest_emrd.episode` imports.
"""

from __future__ import annotations

from pytest_emrd.agent import PROMPT_VERSION
from pytest_emrd.world import world_version


def protocol_version(backend: str = "builtin") -> str:
    """World + prompt protocol version of ``backend``; cassettes and stored results are keyed
    by it (``builtin-4+p2``; ``ai2thor-1+builtin-4+p2``)."""
    return f"{world_version(backend)}+{PROMPT_VERSION}"
