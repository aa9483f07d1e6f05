"""The README opens with the commands CI runs, stays short and links only to what exists."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]
README = ROOT / "README.md"


def _ci_command(name: str) -> str:
    match = re.search(rf'^{name}="(.*)"$', (ROOT / ".ci/run").read_text(), re.MULTILINE)
    assert match, f"{name} missing from .ci/run"
    return match.group(1)


def test_readme_opens_with_the_commands_ci_runs() -> None:
    blocks = re.findall(r"```bash\n(.*?)\n```", README.read_text(), re.DOTALL)
    assert blocks[:2] == [_ci_command("BENCHMARK_COMMAND"), _ci_command("TEST_COMMAND")]


def test_readme_is_short() -> None:
    assert len(README.read_text().splitlines()) <= 350


def test_every_relative_link_of_the_readme_exists() -> None:
    links = re.findall(r"\]\(([^)#]+)(?:#[^)]*)?\)", README.read_text())
    relative = [link for link in links if not re.match(r"[a-z]+:", link)]
    assert relative, "the README links into docs/"
    missing = [link for link in relative if not (ROOT / link).exists()]
    assert not missing, f"README links to missing files: {missing}"


def test_the_readme_is_no_diary() -> None:
    """History belongs to git log: no commit hashes, no load averages, no "previous stop"."""
    text = README.read_text()
    assert not re.search(r"\b(?=[0-9a-f]*\d)(?=[0-9a-f]*[a-f])[0-9a-f]{7,40}\b", text)
    assert not re.search(r"load average|previous (stop|table|release)", text, re.IGNORECASE)
