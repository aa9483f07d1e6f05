"""Self-contained HTML pages of the episode viewer, and the optional GIF (pure: bytes out).

Frames are embedded as the exact JPEG bytes the world renders (base64), the rest as JSON
read by a small inline script (``page.js``): no file or network access from the page.
"""

from __future__ import annotations

import base64
import html
import io
import json
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from typing import Any

from PIL import Image, ImageDraw, ImageFont

from pytest_emrd.view._data import FrameCheck
from pytest_emrd.view._replay import Frame


def _asset(name: str) -> str:
    return resources.files("pytest_emrd.view").joinpath(name).read_text(encoding="utf-8")


def _script_json(value: Any) -> str:
    """JSON safe inside ``<script>`` (no ``</script>`` can close it early)."""
    return json.dumps(value, separators=(",", ":")).replace("</", "<\\/")


def _rationale(data: dict[str, Any]) -> str:
    if data["status"] != "terminated":
        return f"no Term ({data['status']}{': ' + data['error'] if data['error'] else ''})"
    chosen = data["chosen_room"] or f"{data['chosen_raw']!r} (no such room)"
    return f"Term({chosen}): {data['rationale'] or ''}"


def episode_page(data: dict[str, Any], frames: Sequence[Frame]) -> str:
    """The HTML page of one episode (``data`` from :func:`episode_data`)."""
    e = html.escape
    notes = "".join(
        f'<div class="note{" bad" if "differ" in n else ""}">⚠ {e(n)}</div>' for n in data["notes"]
    )
    encoded = [base64.b64encode(f.jpeg).decode() for f in frames]
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8">
<title>{e(data["case_id"])} · EMRD episode</title>
<style>{_asset("page.css")}</style></head>
<body>
<p><a href="index.html">← all episodes</a></p>
<h1>{e(data["case_id"])}</h1>
<div class="meta">model {e(data["model"])} · {e(data["condition"])} · prompt {e(data["variant"])} ·
spawn {e(data["spawn"])} · episode {data["episode"]} · protocol {e(data["protocol"])} ·
{len(data["steps"])} steps · {e(_rationale(data))}</div>
{notes}
<div class="controls"><button id="prev" title="previous step (←)">◀</button>
<input id="slider" type="range" min="0" value="0" aria-label="step">
<button id="next" title="next step (→)">▶</button><span id="stepno"></span></div>
<div class="grid">
 <div class="col">
 <div class="panel"><h2>1 · Before the action: what the model saw (re-rendered)</h2>
  <img id="frame" alt="frame"><div id="frameflag"></div>
  <dl><dt>pose shown</dt><dd id="pose"></dd><dt>in view (truth)</dt><dd id="visible"></dd></dl>
 </div>
 <div class="panel"><h2>2 · The request</h2>
  <details><summary>system prompt (the same at every step)</summary>
  <pre id="system">{e(data["system"] or "not rebuilt (see the notes above)")}</pre></details>
  <div class="cap">this step's text</div><pre id="prompt"></pre>
  <div class="cap" id="windowcap"></div><div id="window" class="thumbs"></div></div>
 <div class="panel"><h2>3 · Reply and action</h2><dl>
  <dt>action</dt><dd id="action"></dd>
  <dt>observation</dt><dd id="observation"></dd><dt>dedup check</dt><dd id="dedup"></dd>
  <dt>reasoning</dt><dd id="reasoning"></dd><dt>parse error</dt><dd id="parse"></dd>
  <dt>tokens</dt><dd id="tokens"></dd><dt>latency</dt><dd id="latency"></dd></dl>
  <details><summary>raw reply</summary><pre id="raw"></pre></details></div>
 <div class="panel result"><h2>4 · Result: the engine's feedback on this action</h2><dl>
  <dt>outcome</dt><dd id="outcome"></dd><dt>feedback</dt><dd id="feedback"></dd>
  <dt>agent after</dt><dd id="after"></dd></dl></div>
 </div>
 <div class="col">
 <div class="panel"><h2>Cognitive map after this step, aligned onto the ground truth (top
  down, in {e(data["plan_frame"])})</h2>
  <svg id="plan" role="img" aria-label="plan" style="aspect-ratio: 1 / 1"></svg>
  <div class="legend"><span style="color:#888">● object</span><span style="color:#f0a800">◯
  in view now</span><span style="color:#1f5fbf">● agent, field of view, path</span>
  <span style="color:#d62728">✕ map entry → its object</span><span style="color:#ff9900">✕
  unmatched entry</span></div><div id="scores"></div></div>
 <div class="panel"><h2>Metrics over time</h2><svg id="chart" role="img" aria-label="metrics">
  </svg><div class="legend"><span style="color:#1f5fbf">— coverage |K|/|E|</span>
  <span style="color:#d62728">- - PA</span><span style="color:#2ca02c">··· TBS(t)</span></div>
 </div>
 </div>
</div>
<script>const DATA = {_script_json(data)};
const FRAMES = {_script_json(encoded)};
{_asset("page.js")}</script>
</body></html>
"""


@dataclass(frozen=True)
class IndexRow:
    """One episode on the index page."""

    case_id: str
    status: str
    steps: int
    chosen: str
    coverage: float | None
    pa: float | None
    check: FrameCheck


def _check_text(c: FrameCheck) -> str:
    if c.mismatched:
        return f"⚠ {len(c.mismatched)} of {c.checked} frames differ"
    if c.checked:
        return f"✓ {c.checked} frames match"
    return "not checked"


def index_page(rows: Sequence[IndexRow]) -> str:
    """The index of every episode page written."""
    e = html.escape
    num = lambda v: "n/a" if v is None else f"{v:.3f}"  # noqa: E731
    body = "".join(
        f'<tr><td><a href="{e(r.case_id)}.html">{e(r.case_id)}</a></td><td>{e(r.status)}</td>'
        f"<td>{r.steps}</td><td>{e(r.chosen)}</td><td>{num(r.coverage)}</td><td>{num(r.pa)}</td>"
        f"<td>{e(_check_text(r.check))}</td></tr>"
        for r in rows
    )
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>EMRD episodes</title>
<style>{_asset("page.css")}</style></head><body><h1>EMRD episodes</h1>
<table><tr><th>episode</th><th>status</th><th>steps</th><th>chosen room</th>
<th>coverage</th><th>PA</th><th>frames vs cassette</th></tr>{body}</table></body></html>
"""


def episode_gif(data: dict[str, Any], frames: Sequence[Frame], *, ms: int = 700) -> bytes:
    """An animated GIF of the frames with the step and action written under each."""
    images = []
    font = ImageFont.load_default(size=15)
    for st in data["steps"]:
        if st["frame"] is None:
            continue
        frame = Image.open(io.BytesIO(frames[st["frame"]].jpeg)).convert("RGB")
        canvas = Image.new("RGB", (frame.width, frame.height + 30), "white")
        canvas.paste(frame, (0, 0))
        mark = "" if st["frame_ok"] is not False else "  [frame differs from recording]"
        text = f"step {st['t']}: {st['action'] or '(none)'}{mark}"
        ImageDraw.Draw(canvas).text((8, frame.height + 6), text, fill="black", font=font)
        images.append(canvas.quantize(colors=128))
    buffer = io.BytesIO()
    if images:
        images[0].save(buffer, format="GIF", save_all=True, append_images=images[1:],
                       duration=ms, loop=0)  # fmt: skip
    return buffer.getvalue()
