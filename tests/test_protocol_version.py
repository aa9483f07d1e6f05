"""pytest_emrd.protocol: the version every pytest process reads, without the episode loop."""

from __future__ import annotations

import subprocess
import sys

from pytest_emrd.agent import PROMPT_VERSION
from pytest_emrd.protocol import protocol_version
from pytest_emrd.world import WORLD_VERSION
from pytest_emrd.world.thor import THOR_VERSION


def test_the_protocol_joins_the_world_and_prompt_versions() -> None:
    assert protocol_version() == f"{WORLD_VERSION}+{PROMPT_VERSION}" == "builtin-7+p3"
    assert protocol_version("ai2thor") == f"{THOR_VERSION}+{WORLD_VERSION}+{PROMPT_VERSION}"


def test_reading_it_imports_neither_the_http_clients_nor_the_simulator() -> None:
    # a resumed worker reads it for every stored episode it reuses
    code = (
        "import sys\n"
        "from pytest_emrd.protocol import protocol_version\n"
        "protocol_version()\n"
        "heavy = {'httpx', 'pytest_emrd.episode', 'pytest_emrd.world._simulator'}\n"
        "print(sorted(heavy & set(sys.modules)))"
    )
    done = subprocess.run([sys.executable, "-c", code], capture_output=True, text=True, check=True)
    assert done.stdout.strip() == "[]"
