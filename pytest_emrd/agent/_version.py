"""Behaviour version of the scripted reference agents, carried in every request they get.

Cassettes store the reference agents' replies, so a change in what a scripted agent does
would otherwise replay stale behaviour silently. The ``model`` field a client sends to a
reference agent is therefore ``<name>@<REFERENCE_VERSION>`` (``scout@ref-3``): a cassette
recorded under an older version no longer matches its requests and fails loudly as drift.
Bump :data:`REFERENCE_VERSION` with every change to what a reference agent replies.
"""

from __future__ import annotations

from typing import Final

from pytest_emrd.errors import ConfigError

REFERENCE_VERSION: Final = "ref-4"


def versioned_id(name: str) -> str:
    """The ``model`` field for reference agent ``name``: ``name@REFERENCE_VERSION``.

    :param name: The agent's registry name (``scout``).
    :returns: The versioned model id (``scout@ref-4``).
    """
    return f"{name}@{REFERENCE_VERSION}"


def agent_name(model: str) -> str:
    """The registry name in a requested ``model`` field (``scout@ref-3`` -> ``scout``); a bare
    name is the current version, another version a :class:`ConfigError` naming both.

    :param model: The ``model`` field of a request.
    :returns: The agent's registry name.
    """
    name, sep, version = model.partition("@")
    if sep and version != REFERENCE_VERSION:
        raise ConfigError(
            f"model={model!r} asks for reference agents version {version!r}, but this "
            f"pytest-emrd runs {REFERENCE_VERSION!r}; re-record the cassette (or request "
            f"{versioned_id(name)!r})."
        )
    return name
