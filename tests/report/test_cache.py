"""A report's statistics saved beside the run: read back only for the very same episode files,
``--episode`` and code; the files written are the same either way; figures drawn in worker
processes are the same bytes."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from perf.report import write_run_dir
from pytest_emrd.cli import main
from pytest_emrd.metrics.synthetic import synthetic_grid
from pytest_emrd.report import (
    _build,
    _cache,
    aggregates_key,
    build_report,
    read_aggregates,
    render_files,
    write_aggregates,
)
from pytest_emrd.report._plots import render_figures
from pytest_emrd.run import load_run_episodes

THRESHOLDS = """\
scout:
  baseline:
    aec: {min: 0.2}
"""


def _run_dir(path: Path, max_steps: int = 26) -> Path:
    """A run directory as a pytest run leaves it: episodes, their heads, saved metrics."""
    write_run_dir(path, synthetic_grid(model="scout", episodes=1, max_steps=max_steps))
    return path


@pytest.fixture
def run_dir(tmp_path: Path) -> Path:
    return _run_dir(tmp_path / "run")


def _report(run_dir: Path, out: Path, *extra: str) -> dict[str, bytes]:
    assert main(["report", str(run_dir), "--out", str(out), *extra]) == 0
    return {p.name: p.read_bytes() for p in sorted(out.iterdir())}


def _no_statistics(monkeypatch: pytest.MonkeyPatch) -> None:
    """Computing any table now fails the test: the report must come from the saved file."""

    def fail(*args: object, **kwargs: object) -> None:
        raise AssertionError("the statistics were computed again")

    monkeypatch.setattr(_build, "ebbinghaus_rows", fail)


def test_second_report_reads_the_statistics_back_and_writes_the_same_files(
    run_dir: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)  # no ./thresholds.yaml
    first = _report(run_dir, tmp_path / "first")
    saved = json.loads(_cache.aggregates_path(run_dir).read_bytes())
    assert saved["key"] == aggregates_key(load_run_episodes([run_dir]), episode=None)
    _no_statistics(monkeypatch)
    assert _report(run_dir, tmp_path / "second") == first


def test_gates_and_notes_are_built_afresh_around_saved_statistics(
    run_dir: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    _report(run_dir, tmp_path / "warm", "--format", "json")  # saved without thresholds
    gates = tmp_path / "gates.yaml"
    gates.write_text(THRESHOLDS)
    _no_statistics(monkeypatch)
    data = json.loads(
        _report(run_dir, tmp_path / "gated", "--format", "json", "--thresholds", str(gates))[
            "report.json"
        ]
    )
    assert [v["metric"] for v in data["gates"]["verdicts"]] == ["aec"]
    assert not any("No thresholds file" in note for note in data["missing"])


def test_a_changed_episode_file_or_episode_option_computes_again(
    run_dir: Path, tmp_path: Path, monkeypatch: pytest.MonkeyPatch
) -> None:
    monkeypatch.chdir(tmp_path)
    _report(run_dir, tmp_path / "first", "--format", "json")
    episodes = load_run_episodes([run_dir])
    key = aggregates_key(episodes, episode=None)
    assert aggregates_key(episodes, episode="scout-texture-office-ep00") != key
    # the same case stored from another trajectory: another file digest, another key
    other = load_run_episodes([_run_dir(tmp_path / "other", max_steps=30)])
    assert [e.head.spec.case_id for e in other] == [e.head.spec.case_id for e in episodes]
    assert aggregates_key(other, episode=None) != key
    assert read_aggregates(run_dir, "0" * 64) is None
    chosen = "scout-low_light-kitchen-ep00"
    data = json.loads(_report(run_dir, tmp_path / "map", "--episode", chosen)["report.json"])
    assert data["episode_map"]["case_id"] == chosen  # not the saved report's episode


def test_episodes_without_a_file_digest_have_no_key(grid, make_run_dir) -> None:
    from pytest_emrd.run import StoredEpisode

    handed = [StoredEpisode.of(t, session="", recorded=False, frame_drift=0, seconds=0.0)
              for t in grid[:2]]  # fmt: skip
    assert aggregates_key(handed, episode=None) is None
    headless = make_run_dir("old", grid[:2])  # written before heads: decoded in full
    assert aggregates_key(load_run_episodes([headless]), episode=None) is None


def test_unreadable_or_unwritable_saves_are_ignored(run_dir: Path, tmp_path: Path) -> None:
    episodes = load_run_episodes([run_dir])
    key = aggregates_key(episodes, episode=None)
    assert key is not None
    path = _cache.aggregates_path(run_dir)
    path.parent.mkdir()
    path.write_text(json.dumps({"key": key, "report": {"schema_version": 99}}))
    assert read_aggregates(run_dir, key) is None
    path.write_bytes(b"\x00not json")
    assert read_aggregates(run_dir, key) is None
    path.unlink()
    path.parent.rmdir()
    path.parent.write_text("a file where the folder would go")  # cannot be written into
    write_aggregates(run_dir, key, build_report(episodes, with_reasoning=False))
    assert read_aggregates(run_dir, key) is None


def test_round_trip_keeps_every_output_byte(run_dir: Path) -> None:
    episodes = load_run_episodes([run_dir])
    report = build_report(episodes, with_reasoning=False)
    key = aggregates_key(episodes, episode=None)
    assert key is not None
    write_aggregates(run_dir, key, report)
    saved = read_aggregates(run_dir, key)
    assert saved == report
    again = build_report(episodes, with_reasoning=False, statistics=saved)
    assert render_files(again, ["md", "json"]) == render_files(report, ["md", "json"])


def test_figures_drawn_in_worker_processes_are_the_same_bytes(run_dir: Path) -> None:
    report = build_report(load_run_episodes([run_dir]), with_reasoning=False)
    one, two = render_figures(report), render_figures(report, processes=2)
    assert two == one
    assert list(two[0]) == list(one[0])  # in FIGURES order


def test_map_aligned_in_a_worker_process_is_the_same_report(run_dir: Path) -> None:
    episodes = load_run_episodes([run_dir])
    here = build_report(episodes, with_reasoning=False)
    assert build_report(episodes, with_reasoning=False, processes=2) == here
    assert here.episode_map is not None
