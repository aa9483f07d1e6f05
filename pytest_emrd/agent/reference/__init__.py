"""Built-in reference agents: scripted, deterministic, served over a local HTTP endpoint.

Profiles (planted cognition, so metrics can be checked against known truth): ``scout``,
``scout-decay-<mean steps>``, ``scout-window-<k>``, ``scout-serial``, ``prior``. Requests
name them by versioned id, ``<name>@<REFERENCE_VERSION>`` (see :mod:`._version`).
"""

from pytest_emrd.agent.reference._agents import complete, reply_text
from pytest_emrd.agent.reference._server import ReferenceServer, reference_base_url
from pytest_emrd.agent.reference._version import REFERENCE_VERSION, agent_name, versioned_id

__all__ = [
    "REFERENCE_VERSION",
    "ReferenceServer",
    "agent_name",
    "complete",
    "reference_base_url",
    "reply_text",
    "versioned_id",
]
