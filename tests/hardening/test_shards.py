"""Probe 5: a partial or duplicated shard set gives no verdict unless --allow-partial."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pytest_emrd.cli import main as emrd
from pytest_emrd.errors import ConfigError
from pytest_emrd.run import (
    RunIdentity,
    check_resume,
    check_shard_set,
    read_identity,
    resolve_settings,
    write_identity,
)

ROOT = Path(__file__).resolve().parents[2]
PROTOCOL = "builtin-3+p1"
GRID = "grid {id}: models gpt; 3 condition(s) x 4 spawn(s) x 20 episode(s)"


def _shard(tmp_path: Path, name: str, shard: str | None) -> Path:
    settings = resolve_settings({"model": ["gpt"], "shard": shard}, {}, rootdir=tmp_path, env={})
    run_dir = tmp_path / name
    (run_dir / "episodes").mkdir(parents=True)
    write_identity(run_dir, RunIdentity.of(settings, PROTOCOL))
    return run_dir


@pytest.fixture
def grid_id(tmp_path: Path) -> str:
    settings = resolve_settings({"model": ["gpt"]}, {}, rootdir=tmp_path, env={})
    return RunIdentity.of(settings, PROTOCOL).grid_id


def test_a_complete_set_passes_and_the_identity_round_trips(tmp_path):
    dirs = [_shard(tmp_path, f"run-{k}", f"{k}/4") for k in (1, 2, 3, 4)]
    assert check_shard_set(dirs) == []
    identity = read_identity(dirs[1])
    assert identity is not None and identity.shard == (2, 4)
    assert RunIdentity.from_dict(identity.to_dict()) == identity
    assert json.loads((dirs[1] / "run.json").read_text())["shard"] == [2, 4]


def test_missing_shards_are_named(tmp_path, grid_id, capsys):
    dirs = [_shard(tmp_path, f"run-{k}", f"{k}/4") for k in (1, 2)]
    expected = (
        "the run directories are not one complete set of shards: "
        f"{GRID.format(id=grid_id)} has 2 of 4 shards (1/4 ({dirs[0]}), 2/4 ({dirs[1]})); "
        "missing 3/4, 4/4. Pass every shard's run directory once, or --allow-partial to gate "
        "on what is there."
    )
    with pytest.raises(ConfigError) as info:
        check_shard_set(dirs)
    assert str(info.value) == expected
    assert emrd(["gate", *map(str, dirs), "--thresholds", str(ROOT / "thresholds.yaml")]) == 2
    assert capsys.readouterr().err == f"emrd gate: error: {expected}\n"


def test_a_shard_given_twice_is_refused(tmp_path, grid_id):
    one, two, again = (
        _shard(tmp_path, n, s) for n, s in (("a", "1/2"), ("b", "2/2"), ("c", "2/2"))
    )
    with pytest.raises(ConfigError, match=r"shard 2/2 of grid \w+: .* is in 2 directories"):
        check_shard_set([one, two, again])
    with pytest.raises(ConfigError, match=r"is given twice \(also as "):
        check_shard_set([one, two, one])


def test_allow_partial_gates_with_a_warning(tmp_path, capsys):
    dirs = [_shard(tmp_path, "run-1", "1/2")]
    thresholds = tmp_path / "gates.yaml"
    thresholds.write_text("gpt:\n  baseline:\n    aec: {min: 0.1}\n")
    code = emrd(["gate", str(dirs[0]), "--thresholds", str(thresholds), "--allow-partial"])
    printed = capsys.readouterr()
    assert code == 0  # told to gate what is there: here nothing, so no gate applies
    assert printed.err.startswith("emrd gate: warning: partial shard set: grid ")
    assert printed.err.rstrip().endswith("missing 2/2")
    assert "0 episodes from 1 run director(ies)" in printed.out


def test_a_run_directory_keeps_its_shard(tmp_path):
    run_dir = _shard(tmp_path, "run", "1/4")
    check_resume(run_dir, (1, 4))
    with pytest.raises(ConfigError) as info:
        check_resume(run_dir, (2, 4))
    assert str(info.value).startswith(f"--emrd-results={run_dir} holds shard 1/4 of grid ")
    assert str(info.value).endswith("this run is 2/4. Give each shard its own run directory.")


@pytest.mark.slow
def test_pytest_records_the_shard_in_the_run_directory(sandbox):
    sandbox.makepyfile(test_emrd=(ROOT / "benchmarks" / "test_emrd.py").read_text())
    run_dir = sandbox.path / "shard"
    result = sandbox.runpytest(
        "-p",
        "no:cacheprovider",
        "--emrd-model=scout",
        "--emrd-condition=baseline",
        "--emrd-spawn=office",
        "--emrd-episodes=2",
        "--emrd-modality=text",
        "--emrd-shard=2/2",
        f"--emrd-results={run_dir}",
    )
    result.assert_outcomes(passed=1, deselected=1)
    identity = read_identity(run_dir)
    assert identity is not None and identity.shard == (2, 2)
    assert identity.grid["models"] == ["scout"] and identity.grid["episodes"] == 2
    again = sandbox.runpytest(
        "-p", "no:cacheprovider", "--emrd-shard=1/2", f"--emrd-results={run_dir}"
    )
    assert again.ret != 0
    again.stderr.fnmatch_lines([f"ERROR: --emrd-results={run_dir} holds shard 2/2 of grid *"])
