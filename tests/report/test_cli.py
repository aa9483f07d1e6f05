"""``emrd report`` end to end on run directories (black box through the console entry)."""

from __future__ import annotations

import json
from pathlib import Path

import pytest

from pytest_emrd.cli import main
from pytest_emrd.metrics.synthetic import synthetic_grid
from pytest_emrd.report import FIGURES
from pytest_emrd.trajectory import Trajectory

THRESHOLDS = """\
scout:
  baseline:
    aec: {min: 0.2}
    never_visited: {max: 0.0}
"""


@pytest.fixture
def run_dir(make_run_dir, grid: list[Trajectory]) -> Path:
    scout = synthetic_grid(model="scout", episodes=1, max_steps=26)
    return make_run_dir("run", scout)


def test_report_writes_every_format(run_dir: Path, tmp_path: Path, capsys) -> None:
    thresholds = tmp_path / "gates.yaml"
    thresholds.write_text(THRESHOLDS)
    out = tmp_path / "out"
    code = main(["report", str(run_dir), "--out", str(out), "--thresholds", str(thresholds)])
    assert code == 0
    names = {p.name for p in out.iterdir()}
    assert names == {"report.md", "report.html", "report.json", *(f.name for f in FIGURES)}
    data = json.loads((out / "report.json").read_text())
    assert [v["metric"] for v in data["gates"]["verdicts"]] == ["aec", "never_visited"]
    assert data["gates"]["source"] == str(thresholds)
    printed = capsys.readouterr().out
    assert printed.startswith("12 episodes from 1 run director(ies)")
    assert "report.html" in printed


def test_default_out_dir_and_format_subset(run_dir: Path, monkeypatch, tmp_path: Path) -> None:
    monkeypatch.chdir(tmp_path)  # no ./thresholds.yaml here
    assert main(["report", str(run_dir), "--format", "json"]) == 0
    assert [p.name for p in (run_dir / "report").iterdir()] == ["report.json"]
    data = json.loads((run_dir / "report" / "report.json").read_text())
    assert any("No thresholds file" in n for n in data["missing"])


def test_shards_make_one_report(make_run_dir, tmp_path: Path) -> None:
    scout = synthetic_grid(model="scout", episodes=1, max_steps=26)
    a, b = make_run_dir("a", scout[::2]), make_run_dir("b", scout[1::2])
    out = tmp_path / "merged"
    assert main(["report", str(a), str(b), "--out", str(out), "--format", "json"]) == 0
    assert json.loads((out / "report.json").read_text())["overview"]["episodes"] == 12


def test_compare_prints_markdown_or_writes_files(make_run_dir, tmp_path: Path, capsys) -> None:
    a = make_run_dir("a", synthetic_grid(model="scout", episodes=2, max_steps=26))
    b = make_run_dir("b", synthetic_grid(model="scout", episodes=2, max_steps=26,
                                         mean_memory=3.0))  # fmt: skip
    assert main(["report", "--compare", str(a), str(b)]) == 0
    md = capsys.readouterr().out
    assert md.startswith("# EMRD comparison") and "| memory_strength | higher |" in md
    out = tmp_path / "cmp"
    assert main(["report", "--compare", str(a), str(b), "--out", str(out)]) == 0
    assert {p.name for p in out.iterdir()} == {"compare.md", "compare.html", "compare.json"}
    said = capsys.readouterr().out  # the verdicts in the terminal, then the files
    assert "scout baseline memory_strength: " in said and said.rstrip().endswith("compare.json")


def test_compare_models_within_one_run(make_run_dir, capsys) -> None:
    run = make_run_dir(
        "run",
        synthetic_grid(model="scout", episodes=2, max_steps=26)
        + synthetic_grid(model="cand", episodes=2, max_steps=26, mean_memory=3.0),
    )
    assert main(["report", str(run), "--compare-models", "scout", "cand"]) == 0
    md = capsys.readouterr().out
    assert "*scout vs cand, Baseline*" in md and "| memory_strength | higher |" in md
    assert "**worse**" in md
    assert main(["report", str(run), "--compare-models", "scout", "gpt"]) == 2
    assert "compare-models='gpt' is not one of 'cand', 'scout'" in capsys.readouterr().err


@pytest.mark.parametrize(
    ("argv", "message"),
    [
        (["report"], "give either RUN_DIR... or --compare RUN_A RUN_B"),
        (["report", "x", "--compare", "a", "b"], "give either RUN_DIR... or --compare"),
        (["report", "x", "--format", "md,pdf"], "format='pdf' is not one of"),
        (
            ["report", "nowhere"],
            "RUN_DIR nowhere does not exist; pass the folder a pytest run wrote",
        ),
    ],
    ids=["neither", "both", "bad-format", "not-a-run-dir"],
)
def test_usage_errors_exit_2(argv: list[str], message: str, capsys, tmp_path, monkeypatch) -> None:
    monkeypatch.chdir(tmp_path)
    assert main(argv) == 2
    assert message in capsys.readouterr().err


def test_episode_option_picks_the_map_figure_episode(run_dir: Path, tmp_path: Path) -> None:
    out = tmp_path / "out"
    chosen = "scout-low_light-kitchen-ep00"
    assert main(["report", str(run_dir), "--out", str(out), "--episode", chosen]) == 0
    data = json.loads((out / "report.json").read_text())
    assert data["episode_map"]["case_id"] == chosen
    assert chosen in (out / "report.md").read_text()


def test_unknown_episode_names_the_run_s_case_ids(run_dir: Path, tmp_path: Path, capsys) -> None:
    code = main(["report", str(run_dir), "--out", str(tmp_path), "--episode", "scout-nope-ep99"])
    assert code == 2
    err = capsys.readouterr().err
    assert "episode='scout-nope-ep99' is not in the run (12 episodes: scout-baseline-" in err


@pytest.mark.parametrize(
    "needles",
    [
        ("Eq. SPE", "censoring-aware", "Eq. SMLE"),
        ("X: other room", "X: no Term", "Spawn room (%)"),
    ],
    ids=["both-serial-position-estimators", "other-split-and-spawn-room-share"],
)
def test_markdown_and_html_carry_the_protocol_tables(
    run_dir: Path, tmp_path: Path, needles: tuple[str, ...]
) -> None:
    out = tmp_path / "out"
    assert main(["report", str(run_dir), "--out", str(out), "--format", "md,html"]) == 0
    for name in ("report.md", "report.html"):
        text = (out / name).read_text()
        assert all(n in text for n in needles), (name, needles)


def test_a_report_leaves_the_run_directory_as_it_was_and_repeats_itself(
    run_dir: Path, tmp_path: Path, monkeypatch
) -> None:
    monkeypatch.chdir(tmp_path)  # no ./thresholds.yaml here
    before = sorted(p.relative_to(run_dir) for p in run_dir.rglob("*"))
    written = []
    for name in ("first", "second"):
        assert main(["report", str(run_dir), "--out", str(tmp_path / name)]) == 0
        written.append({p.name: p.read_bytes() for p in (tmp_path / name).iterdir()})
    assert sorted(p.relative_to(run_dir) for p in run_dir.rglob("*")) == before
    assert written[0] == written[1]


def test_an_old_layout_run_directory_is_reported(grid: list[Trajectory], tmp_path: Path) -> None:
    """Episode files without a head line, with ``heads/`` and ``metrics/`` beside them."""
    run = tmp_path / "old"
    for folder in ("episodes", "heads", "metrics"):
        (run / folder).mkdir(parents=True)
    for t in grid:
        legacy = {"store_schema": 1, "session": "s", "recorded": False, "frame_drift": 0,
                  "seconds": 0.1, "trajectory": t.to_dict()}  # fmt: skip
        (run / "episodes" / f"{t.spec.case_id}.json").write_text(json.dumps(legacy))
        (run / "heads" / f"{t.spec.case_id}.json").write_text('{"stale": true}')
    out = tmp_path / "out"
    assert main(["report", str(run), "--out", str(out), "--format", "json"]) == 0
    assert json.loads((out / "report.json").read_text())["overview"]["episodes"] == len(grid)


def test_the_command_prints_it_or_writes_a_new_file(make_run_dir, tmp_path, capsys) -> None:
    run = make_run_dir("run", synthetic_grid(model="scout", episodes=2, max_steps=26))
    assert main(["thresholds", str(run)]) == 0
    assert "scout:\n  baseline:\n" in capsys.readouterr().out
    out = tmp_path / "thresholds.yaml"
    assert main(["thresholds", str(run), "--out", str(out)]) == 0
    assert f"check them: emrd gate {run} --thresholds {out}" in capsys.readouterr().out
    assert main(["thresholds", str(run), "--out", str(out)]) == 2
    assert "never overwrites" in capsys.readouterr().err
