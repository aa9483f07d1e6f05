"""Built-in reference agents: scripted, deterministic, served over a local HTTP endpoint.

Profiles with planted cognition, so metrics can be checked against known truth
(docs/user-guide/reference-agents.md). Their knobs and behaviour version are the registry's
(:mod:`pytest_emrd.agent`). Names are imported on first use.
"""

from pytest_emrd._lazy import lazy_exports

__getattr__, __dir__, __all__ = lazy_exports(
    __name__,
    {
        "_agents": ("complete", "reply_text"),
        "_malform": ("read_state",),
        "_server": ("ReferenceServer", "base_url_of", "reference_base_url"),
    },
)
