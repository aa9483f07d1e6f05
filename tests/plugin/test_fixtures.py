"""The ``emrd_*`` session fixtures are extension points: a ``conftest.py`` override of the
settings, the cassette folder or the record mode changes how the episodes run."""

from __future__ import annotations

import re
import shutil
from pathlib import Path

import pytest

import pytest_emrd.plugin as plugin
from tests._sandbox import Sandbox

pytestmark = pytest.mark.slow

SETTINGS = """
import dataclasses
import pathlib

import pytest


@pytest.fixture(scope="session")
def emrd_settings(emrd_settings):
    return dataclasses.replace(emrd_settings, cassettes=pathlib.Path({copy!r}))
"""

CASSETTE_DIR = """
import pytest


@pytest.fixture(scope="session")
def emrd_cassette_dir():
    return {copy!r}
"""


@pytest.mark.parametrize("conftest", [SETTINGS, CASSETTE_DIR], ids=["settings", "cassette_dir"])
def test_an_overridden_cassette_folder_is_the_one_replayed(
    suite: Sandbox, small, recorded, conftest: str
):
    copy = suite.path / "elsewhere"
    shutil.copytree(recorded, copy)
    before = sorted(p.relative_to(copy) for p in copy.rglob("*"))
    suite.makeconftest(conftest.format(copy=str(copy)))
    empty = suite.path / "empty"
    empty.mkdir()
    result = suite.runpytest(*small(f"--emrd-cassettes={empty}", "--emrd-record-mode=once"))
    result.assert_outcomes(passed=4)
    assert not any(empty.iterdir()), "the episodes were recorded into --emrd-cassettes"
    assert sorted(p.relative_to(copy) for p in copy.rglob("*")) == before


def test_an_overridden_record_mode_is_the_one_used(suite: Sandbox, small):
    suite.makeconftest(
        "import pytest\n\n\n@pytest.fixture(scope='session')\n"
        "def emrd_record_mode():\n    return 'none'\n"
    )
    empty = suite.path / "empty"
    empty.mkdir()
    result = suite.runpytest(
        *small(f"--emrd-cassettes={empty}", "--emrd-record-mode=once", episodes=1)
    )
    result.assert_outcomes(failed=3)
    result.stdout.fnmatch_lines(["*scout-baseline-office-ep00*cassette*"])
    assert not any(empty.iterdir()), "an episode was recorded in record mode none"


def test_an_override_cannot_change_the_collected_grid(suite: Sandbox, small, recorded):
    suite.makeconftest(
        "import dataclasses\n\nimport pytest\n\n\n@pytest.fixture(scope='session')\n"
        "def emrd_settings(emrd_settings):\n"
        "    return dataclasses.replace(emrd_settings, episodes=5)\n"
    )
    result = suite.runpytest(*small(f"--emrd-cassettes={recorded}", "--emrd-record-mode=none"))
    result.assert_outcomes(errors=4)
    result.stdout.fnmatch_lines(["*emrd_settings fixture changes episodes*--emrd-*"])


def test_the_fixtures_reference_has_one_row_per_fixture():
    page = Path(__file__).parents[2] / "docs" / "reference" / "fixtures.md"
    rows = re.findall(r"^\| `(\w+)` \|", page.read_text(encoding="utf-8"), re.MULTILINE)
    fixtures = [name for name in vars(plugin) if name.startswith(("emrd_", "_emrd_"))]
    parameters = ["emrd_spec", "emrd_gate"]  # pytest_generate_tests parametrises these
    assert sorted(rows) == sorted(fixtures + parameters)
