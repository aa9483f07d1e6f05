"""``emrd render`` writes the spawn view, a sweep and a top-down plan."""

from __future__ import annotations

from pathlib import Path

import pytest
from PIL import Image

from pytest_emrd.cli import main


def test_render_writes_frames_and_map(tmp_path: Path, capsys: pytest.CaptureFixture) -> None:
    out = tmp_path / "views"
    assert (
        main(
            [
                "render",
                "--episode",
                "3",
                "--condition",
                "low_light",
                "--spawn",
                "kitchen",
                "--out",
                str(out),
            ]
        )
        == 0
    )
    frames = sorted(out.glob("*.jpg"))
    assert [f.name for f in frames] == [
        "00_spawn.jpg",
        "01_right.jpg",
        "02_behind.jpg",
        "03_left.jpg",
    ]
    for f in frames:
        with Image.open(f) as im:
            assert (im.format, im.size) == ("JPEG", (512, 512))
    with Image.open(out / "map.png") as plan:
        assert plan.format == "PNG" and plan.size[0] > 400
    printed = capsys.readouterr().out
    assert "paper layouts, kitchen ep03" in printed and "low_light, spawn in Kitchen" in printed
    assert "Turn(Right) succeeded" in printed and "Visible:" in printed


@pytest.mark.parametrize(
    "argv",
    [["--spawn", "attic"], ["--episode", "x"], ["--condition", "dark"], ["--layouts", "many"]],
    ids=["bad-spawn", "bad-episode", "bad-condition", "bad-layouts"],
)
def test_render_rejects_bad_arguments(tmp_path: Path, argv: list[str]) -> None:
    with pytest.raises(SystemExit) as exc:
        main(["render", *argv, "--out", str(tmp_path)])
    assert exc.value.code == 2


def test_render_draws_the_world_of_the_episode_spec(tmp_path: Path) -> None:
    """``emrd render`` and the episode loop start from the same world (episode_world)."""
    from pytest_emrd.trajectory import EpisodeSpec
    from pytest_emrd.world import episode_world, make_simulator

    for layouts in ("paper", "generated"):
        out = tmp_path / layouts
        argv = ["render", "--spawn", "entrance", "--episode", "4", "--layouts", layouts]
        assert main([*argv, "--out", str(out)]) == 0
        spec = EpisodeSpec("m", "baseline", "entrance", 4, layouts=layouts)
        world = episode_world(spec)
        first = make_simulator().reset(world.layout, "baseline", world.spawn_room, world.seed)
        assert (out / "00_spawn.jpg").read_bytes() == first.jpeg
