"""``emrd thor-smoke`` on the strict fake: it runs, records and compares what it says."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pytest_emrd.cli import main as emrd
from pytest_emrd.cli.thor_smoke import run_smoke
from pytest_emrd.trajectory import CONDITIONS


def test_one_episode_per_condition_on_both_backends(fake_controller: type, tmp_path: Path) -> None:
    results = run_smoke(
        spawn="office",
        episode=0,
        layouts="paper",
        out=tmp_path,
        backend_options={"controller_factory": fake_controller},
    )
    assert [r.condition for r in results] == list(CONDITIONS)
    assert len(fake_controller.instances) == 1  # one THOR controller for all conditions
    for result in results:
        assert result.ok, "\n".join(result.lines())
        assert result.thor.spec.backend == "ai2thor" and result.builtin.spec.backend == "builtin"
        saved = json.loads((tmp_path / f"{result.condition}-ai2thor.json").read_text())
        assert saved["spec"]["condition"] == result.condition
        text = "\n".join(result.lines())
        assert text.startswith(f"{result.condition}: OK") and "rooms visited" in text


def test_a_missing_build_exits_2_naming_the_fix(
    tmp_path: Path, capsys: pytest.CaptureFixture[str]
) -> None:
    missing = tmp_path / "thor-CloudRendering-missing"
    code = emrd(["thor-smoke", "--out", str(tmp_path), "--local-executable-path", str(missing)])
    assert code == 2 and "local_executable_path=" in capsys.readouterr().err
