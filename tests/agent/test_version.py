"""The behaviour version in reference-agent ids: stale cassettes must fail loudly."""

from __future__ import annotations

import pytest

from pytest_emrd.agent import REFERENCE_VERSION, agent_name, versioned_id
from pytest_emrd.errors import ConfigError


def test_versioned_id_round_trips() -> None:
    assert versioned_id("scout-decay-8") == f"scout-decay-8@{REFERENCE_VERSION}"
    assert agent_name(versioned_id("scout-decay-8")) == "scout-decay-8"


def test_bare_name_means_the_current_version() -> None:
    assert agent_name("prior") == "prior"


@pytest.mark.parametrize("stale", ["scout@ref-1", "scout@", "scout@ref-99"], ids=str)
def test_other_versions_are_refused_naming_both(stale: str) -> None:
    with pytest.raises(ConfigError, match=f"model={stale!r}.*runs {REFERENCE_VERSION!r}") as exc:
        agent_name(stale)
    assert "re-record the cassette" in str(exc.value)
