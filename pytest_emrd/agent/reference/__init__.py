"""Built-in reference agents: scripted, deterministic, served over a local HTTP endpoint.

Profiles with planted cognition, so metrics can be checked against known truth
(docs/user-guide/reference-agents.md). Names are imported on first use: the registry reads
the agents' knobs and versions without loading the agents or their server.
"""

from pytest_emrd._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(
    __name__,
    {
        "_agents": ("complete", "reply_text"),
        "_server": ("ReferenceServer", "reference_base_url"),
        "_version": ("REFERENCE_VERSION", "agent_name", "versioned_id"),
    },
)
