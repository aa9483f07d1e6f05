"""The README's opening commands are the ones CI runs."""

from __future__ import annotations

import re
from pathlib import Path

ROOT = Path(__file__).resolve().parents[1]


def _ci_command(name: str) -> str:
    match = re.search(rf'^{name}="(.*)"$', (ROOT / ".ci/run").read_text(), re.MULTILINE)
    assert match, f"{name} missing from .ci/run"
    return match.group(1)


def test_readme_opens_with_the_commands_ci_runs() -> None:
    blocks = re.findall(r"```bash\n(.*?)\n```", (ROOT / "README.md").read_text(), re.DOTALL)
    assert blocks[:2] == [_ci_command("BENCHMARK_COMMAND"), _ci_command("TEST_COMMAND")]


def test_readme_prints_the_system_prompt_the_code_builds() -> None:
    """The paper's prompt figures are blank, so the README's copy is the reference others cite."""
    from pytest_emrd.agent import build_system_prompt
    from pytest_emrd.world import paper_office

    text = (ROOT / "README.md").read_text()
    section = text.split("## The paper's protocol: one office, one prompt", 1)[1]
    printed = re.search(r"```text\n(.*?)\n```", section, re.DOTALL)
    assert printed, "the README's protocol section lost its ```text block"
    code = build_system_prompt(paper_office().inventory(), "default", modality="vision")
    assert printed.group(1) == code


def test_readme_states_the_paper_office_as_built() -> None:
    from pytest_emrd.world import paper_office

    office = paper_office()
    text = " ".join((ROOT / "README.md").read_text().split())
    assert f"{office.width} m × {office.depth} m" in text
    for room in office.rooms:
        size = f"({room.x1 - room.x0:.1f} × {room.z1 - room.z0:.1f} m)"
        assert re.search(rf"{room.name} (top|bottom)-(left|right) {re.escape(size)}", text), room
    assert f"adjacent rooms; {len(office.objects)} objects" in text
