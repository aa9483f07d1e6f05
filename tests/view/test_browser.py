"""The episode page in a real headless browser (Debian's chromium): the script runs, the
slider position comes from ``#step=N``, the frame, its digest check, the map and the chart
are drawn.

Without a browser the test is skipped with the install command, except where
``EMRD_REQUIRE_BROWSER=1`` (``.ci/run`` sets it after installing chromium): there a missing
browser is a failure, never a silent skip.
"""

from __future__ import annotations

import io
import os
import re
import shutil
import subprocess
import tempfile
from pathlib import Path

import pytest
from PIL import Image

from pytest_emrd.trajectory import Trajectory
from pytest_emrd.view import (
    FrameCheck,
    IndexRow,
    Recorded,
    episode_data,
    episode_page,
    index_page,
    recorded_digests,
    replay_frames,
)

FLAGS = (
    "--headless",
    "--no-sandbox",
    "--disable-gpu",
    "--disable-quic",
    "--no-first-run",
    "--disable-background-networking",
    "--disable-component-update",
    "--disable-sync",
)


@pytest.fixture(scope="module")
def chromium() -> str:
    found = next(filter(None, map(shutil.which, ("chromium", "chromium-browser"))), None)
    if found is None:
        message = "no chromium on PATH: apt-get install -y chromium (Debian) to run this test"
        if os.environ.get("EMRD_REQUIRE_BROWSER") == "1":
            pytest.fail(message)
        pytest.skip(message)
    return found


def browse(chromium: str, page: Path, step: int, *extra: str) -> subprocess.CompletedProcess:
    with tempfile.TemporaryDirectory() as profile:
        return subprocess.run(
            [chromium, *FLAGS, f"--user-data-dir={profile}", *extra,
             f"{page.as_uri()}#step={step}"],
            capture_output=True, text=True, timeout=120, check=True,
        )  # fmt: skip


@pytest.fixture(scope="module")
def pages(episode: Trajectory, cassettes: Path, tmp_path_factory) -> tuple[Path, Path]:
    """The real page, and one whose step-4 digest was altered (as after a world change)."""
    out = tmp_path_factory.mktemp("view")
    frames = replay_frames(episode).frames
    recorded = recorded_digests(episode, cassettes)
    good = out / "good.html"
    good.write_text(episode_page(episode_data(episode, frames, recorded)[0], frames))
    digests = list(recorded.digests)
    digests[3] = "pixels:" + "f" * 64
    bad = out / "bad.html"
    bad.write_text(episode_page(episode_data(episode, frames, Recorded(tuple(digests)))[0],
                                frames))  # fmt: skip
    return good, bad


def by_id(dom: str, element_id: str) -> str:
    match = re.search(rf'id="{element_id}"[^>]*>([^<]*)<', dom)
    assert match, element_id
    return match.group(1)


def test_the_hash_opens_a_step_and_everything_is_drawn(chromium, pages, episode) -> None:
    dom = browse(chromium, pages[0], 5, "--dump-dom").stdout
    assert by_id(dom, "stepno") == f"step 5 / {len(episode.steps)}"
    assert by_id(dom, "frameflag") == "✓ frame matches the recorded digest"
    assert by_id(dom, "action").startswith(episode.steps[4].action)
    assert re.search(r'<img id="frame"[^>]*src="data:image/jpeg;base64,', dom)
    plan = dom[dom.index('id="plan"') : dom.index("</svg>", dom.index('id="plan"'))]
    entries = len(episode.steps[4].cognitive_map)
    assert plan.count("<title>") >= len(episode.ground_truth.objects) + entries
    assert dom.count("<polyline") >= 4  # path + three metric curves
    # the map is the one after step 5's action: the agent stands where that action took it
    after = episode_data(episode, [], Recorded(()))[0]["steps"][5]["at"]
    assert f'<circle cx="{after[0]}" cy="{-after[1]}"' in plan


def test_a_changed_frame_shows_a_warning_on_its_step(chromium, pages) -> None:
    dom = browse(chromium, pages[1], 4, "--dump-dom").stdout
    assert by_id(dom, "frameflag").startswith("⚠ re-rendered frame differs")
    assert "differ from the recorded digest (steps 4)" in dom
    assert by_id(browse(chromium, pages[1], 3, "--dump-dom").stdout, "frameflag").startswith("✓")


def test_the_screenshot_shows_the_frame(chromium, pages, tmp_path: Path) -> None:
    shot = tmp_path / "shot.png"
    browse(chromium, pages[0], 12, f"--screenshot={shot}", "--window-size=1280,1000")
    image = Image.open(io.BytesIO(shot.read_bytes())).convert("RGB")
    assert image.size == (1280, 1000)
    # the rendered frame (top left) is a photo-like image, not an empty box
    frame = image.crop((30, 200, 530, 650))
    assert len(frame.getcolors(maxcolors=1 << 16) or range(1 << 16)) > 500


def test_the_step_reads_in_order_with_request_tokens_latency_and_result(
    chromium, episode, tmp_path: Path
) -> None:
    """The page with the rebuilt request: the step's text, the window's frames, tokens,
    latency, and the engine's feedback under "Result", in that order on the screen."""
    replay = replay_frames(episode)
    data, _ = episode_data(episode, replay.frames, Recorded(()), None, replay.spawn,
                           replay.system)  # fmt: skip
    page = tmp_path / "page.html"
    page.write_text(episode_page(data, replay.frames))
    dom = browse(chromium, page, 12, "--dump-dom").stdout
    step = episode.steps[11]
    assert by_id(dom, "feedback") == step.feedback
    assert by_id(dom, "outcome") == ("executed" if step.success else "not executed")
    assert by_id(dom, "tokens") == (f"{step.usage.prompt_tokens:,} prompt + "
                                    f"{step.usage.completion_tokens:,} completion")  # fmt: skip
    assert re.fullmatch(r"\d+\.\d\d s", by_id(dom, "latency"))
    assert episode.steps[10].feedback in by_id(dom, "prompt")
    assert by_id(dom, "windowcap") == "frames in the request's history window: steps 3–12"
    window = dom[dom.index('id="window"') : dom.index("</div>", dom.index('id="window"'))]
    assert window.count("<img") == 10 and "t=12 (now)" in window
    shot = tmp_path / "step.png"
    browse(chromium, page, 12, f"--screenshot={shot}", "--window-size=1280,2200")
    assert Image.open(shot).size == (1280, 2200)


def test_the_index_has_the_new_columns_and_sorts_by_a_click(chromium, tmp_path: Path) -> None:
    def row(case: str, aec: float | None, parse: int) -> IndexRow:
        metrics = {"aec": aec, "te": 9, "pa": None, "precision": 1.0, "never_visited": False}
        check = FrameCheck(0, (), None)
        return IndexRow(case, "terminated", 10, "Office", metrics, check, parse, tokens=12345)

    page = tmp_path / "index.html"
    page.write_text(index_page([row("a", 0.5, 2), row("b", None, 0), row("c", 0.2, 7)]))
    # a click on the aec header, as a user would, before the DOM is dumped
    script = tmp_path / "click.html"
    script.write_text(
        page.read_text().replace(
            "</body>", "<script>document.querySelectorAll('th')[4].click()</script></body>"
        )
    )
    dom = browse(chromium, script, 0, "--dump-dom").stdout
    for head in (
        "aec",
        "te",
        "pa",
        "precision",
        "parse failures",
        "failed actions",
        "tokens",
        "error",
    ):
        assert re.search(f"<th[^>]*>{head}</th>", dom), head
    cases = re.findall(r'<a href="(\w)\.html">', dom)
    assert cases == ["c", "a", "b"]  # ascending by aec, n/a last
    assert "12,345" in dom
    shot = tmp_path / "index.png"
    browse(chromium, page, 0, f"--screenshot={shot}", "--window-size=1400,400")
    assert Image.open(shot).size == (1400, 400)
