"""The HTML report in a real headless browser at 1400 px: figures two to a row (skipped
without chromium, as tests/view/test_browser.py)."""

from __future__ import annotations

import re
import shutil
import subprocess
from pathlib import Path

import pytest

from pytest_emrd.report import build_report, render_files
from pytest_emrd.trajectory import Trajectory

#: Writes each figure's top edge into the page before chromium dumps it.
PROBE = (
    "<script>document.body.dataset.tops = [...document.querySelectorAll('figure')]"
    ".map((f) => f.offsetTop).join(' ')</script></body>"
)


def test_figures_stand_two_to_a_row_at_1400_px(grid: list[Trajectory], tmp_path: Path) -> None:
    chromium = shutil.which("chromium")
    if chromium is None:
        pytest.skip("no chromium on PATH: apt-get install -y chromium (Debian)")
    html = render_files(build_report(grid[:24], with_reasoning=False), ["html"])["report.html"]
    page = tmp_path / "report.html"
    page.write_text(html.decode().replace("</body>", PROBE))
    flags = ["--headless", "--no-sandbox", "--disable-gpu", "--window-size=1400,1000"]
    dom = subprocess.run(
        [chromium, *flags, f"--user-data-dir={tmp_path / 'profile'}", "--dump-dom", page.as_uri()],
        capture_output=True,
        text=True,
        timeout=120,
        check=True,
    ).stdout
    match = re.search(r'data-tops="([\d ]+)"', dom)
    assert match, dom[-2000:]
    tops = [int(t) for t in match[1].split()]
    assert len(tops) >= 4 and tops[0] == tops[1] and tops[2] == tops[3] > tops[0], tops
