"""Built-in reference agents: scripted, deterministic, served over a local HTTP endpoint.

Profiles (planted cognition, so metrics can be checked against known truth): ``scout``,
``scout-decay-<mean steps>``, ``scout-window-<k>``, ``scout-serial``, ``prior``.
"""

from pytest_emrd.agent.reference._agents import complete, reply_text
from pytest_emrd.agent.reference._server import ReferenceServer, reference_base_url

__all__ = ["ReferenceServer", "complete", "reference_base_url", "reply_text"]
