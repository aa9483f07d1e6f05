"""The episode viewer's pages (pure: data in, HTML text and GIF bytes out).

A step is laid out in the order the model lived it: the frame and pose shown *before* the
action, the request (system prompt, this step's text, the history window's frames), the reply
and its action, then the engine's feedback on it, the *result*. Per step ``t`` the map ``M_t``
is matched by :func:`pytest_emrd.metrics.step_matchings` (as every episode metric does),
aligned with the report's :func:`~pytest_emrd.report.align_map`, and scored with the metrics'
own terms: coverage ``|K| / |E|`` (:func:`aec_score`), Positional Accuracy
(:func:`positional_accuracy_score`) and ``TBS(t)``. Frames are embedded as the exact JPEG
bytes the world renders (base64), the rest as JSON read by the inline script ``page.js``: the
page reads no file and no network.
"""

from __future__ import annotations

import base64
import html
import io
import json
from collections.abc import Sequence
from dataclasses import dataclass
from importlib import resources
from itertools import chain, repeat
from typing import Any, Final

from PIL import Image, ImageDraw, ImageFont

from pytest_emrd.agent import HISTORY_TURNS, parse_reply
from pytest_emrd.metrics import (
    aec_score,
    episode_metrics,
    positional_accuracy_score,
    step_matchings,
)
from pytest_emrd.report import align_map
from pytest_emrd.trajectory import Trajectory
from pytest_emrd.world import WorldPose, local_to_world


@dataclass(frozen=True)
class Frame:
    """One re-rendered observation ``o_{t-1}``, the frame shown at step ``t``."""

    jpeg: bytes
    digest: str
    """Pixel digest the world computed (``pixels:`` + SHA-256), as a cassette records it."""
    text: str = ""
    """The user turn's text shown with this frame (feedback of the previous action, pose,
    step counter, and under ``text``/``both`` the symbolic list), as the loop built it."""


@dataclass(frozen=True)
class Recorded:
    """The frame digests a cassette holds for one episode, or why there are none."""

    digests: tuple[str | None, ...]
    """Per request (= per step), the digest of the newest image it carries (None: none)."""
    note: str | None = None
    latencies: tuple[float | None, ...] = ()
    """Per request, the seconds the live request took when it was recorded (None: unknown)."""


@dataclass(frozen=True)
class FrameCheck:
    """How the re-rendered frames compare with the cassette's digests."""

    checked: int
    mismatched: tuple[int, ...]
    """Steps whose re-rendered frame differs from the recorded one."""
    note: str | None
    """Why some or all steps are not checked."""


def _round(x: float | None) -> float | None:
    return None if x is None else round(x, 3)


def episode_data(
    traj: Trajectory,
    frames: Sequence[Frame],
    recorded: Recorded,
    note: str | None = None,
    spawn: WorldPose | None = None,
    system: str | None = None,
) -> tuple[dict[str, Any], FrameCheck]:
    """The JSON the page script reads (frames by index into ``frames``) and the frame check.

    The plan (rooms, objects, the aligned map, the agent) is drawn in the office's own frame
    when ``spawn`` (the spawn pose in it) is known, so every episode of an office reads north
    up; the pose line keeps the spawn-frame odometry the model was shown. ``system`` is the
    system prompt of the episode (None: not rebuilt).

    :param traj: The episode.
    :param frames: The re-rendered frames.
    :param recorded: The cassette's frame digests, for the check.
    :param note: Why frames are missing, if they are.
    :param spawn: The spawn pose in the office's frame, if known.
    :param system: The system prompt, if rebuilt.
    :returns: ``(data, check)``: the page's JSON and the :class:`FrameCheck`.
    """

    def place(x: float, z: float) -> tuple[float, float]:
        """Spawn frame -> the office's frame (the identity without ``spawn``), to the mm."""
        if spawn is not None:
            x, z = local_to_world(spawn.x, spawn.z, spawn.heading, x, z)
        return round(x, 3), round(z, 3)

    turn = spawn.heading if spawn else 0.0
    spec, truth = traj.spec, traj.ground_truth
    measured = episode_metrics(traj)
    tbs = measured.tbs
    # per step: True (digest equal), False (mismatch) or None (not checked)
    digests = chain(recorded.digests, repeat(None))
    status = [None if d is None else d == f.digest for f, d in zip(frames, digests, strict=False)]
    bad = tuple(i + 1 for i, s in enumerate(status) if s is False)
    check = FrameCheck(sum(s is not None for s in status), bad, recorded.note)
    steps = []
    matchings = step_matchings([s.cognitive_map for s in traj.steps], truth.objects)
    following = [*traj.steps[1:], None]
    for i, (s, matching, after) in enumerate(zip(traj.steps, matchings, following, strict=True)):
        points, rotation, rmse = align_map(s.cognitive_map, matching)
        reply = parse_reply(s.raw_reply)
        pose, shown = s.pose, i < len(frames)  # shown: a frame was re-rendered for the step
        steps.append(
            {
                "t": s.index,
                "action": s.action,
                "success": s.success,
                "feedback": s.feedback,
                "parse_error": s.parse_error,
                "observation": reply.observation,
                "dedup": reply.dedup_check,
                "reasoning": reply.reasoning,
                "raw": s.raw_reply,
                "pose": [round(pose.x, 3), round(pose.z, 3), round(pose.heading, 1)],
                "at": [*place(pose.x, pose.z), round((pose.heading + turn) % 360.0, 1)],
                "room": s.room,
                "visible": list(s.visible_ids),
                "map": [[p.label, *place(p.x, p.z), p.object_id] for p in points],
                "rotation": round(rotation, 1),
                "rmse": _round(rmse),
                "coverage": _round(aec_score(matching, len(truth.objects))),
                "pa": _round(positional_accuracy_score(matching, len(truth.discoverable_ids))),
                "tbs": _round(tbs[i]) if i < len(tbs) else None,
                "frame": i if shown else None,
                "frame_ok": status[i] if shown else None,
                "prompt": frames[i].text or None if shown else None,
                "window": list(range(max(0, i - HISTORY_TURNS + 1), min(i + 1, len(frames)))),
                "tokens": [s.usage.prompt_tokens, s.usage.completion_tokens],
                "latency": s.latency_s,
                "recorded_latency": recorded.latencies[i] if i < len(recorded.latencies) else None,
                "after": (
                    f"{after.room} (x={after.pose.x:.2f} z={after.pose.z:.2f} "
                    f"heading={after.pose.heading:.0f}°)"
                    if after
                    else traj.final_room
                ),
            }
        )
    notes = [n for n in (note, check.note) if n]
    if check.mismatched:
        notes.insert(
            0,
            f"{len(check.mismatched)} re-rendered frame(s) differ from the recorded "
            f"digest (steps {', '.join(map(str, check.mismatched))}): the world changed "
            "since recording; those frames are not what the model saw",
        )
    data = {
        "case_id": spec.case_id,
        "model": spec.model,
        "condition": spec.condition,
        "variant": spec.variant,
        "spawn": spec.spawn,
        "episode": spec.episode,
        "status": traj.status,
        "protocol": traj.protocol,
        "chosen_room": traj.chosen_room,
        "chosen_raw": traj.chosen_room_raw,
        "rationale": traj.rationale,
        "error": traj.error,
        "final_room": traj.final_room,
        "notes": notes,
        "system": system,
        "plan_frame": "the office's frame, north up" if spawn else "the spawn frame",
        "rooms": [
            {"name": r.name, "polygon": [list(place(*p)) for p in r.polygon]} for r in truth.rooms
        ],
        "objects": [
            [o.object_id, o.object_type, o.category, *place(o.x, o.z)] for o in truth.objects
        ],
        "steps": steps,
        "metrics": {name: getattr(measured, name) for name in INDEX_METRICS},
    }
    return data, check


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
    """The HTML page of one episode (``data`` from :func:`episode_data`).

    :param data: The page's JSON.
    :param frames: The frames it indexes.
    :returns: The HTML text.
    """
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


#: The gate metrics the index shows per episode (``EpisodeMetrics`` fields), in its order.
INDEX_METRICS: Final = ("aec", "te", "pa", "precision", "fpsg_local", "never_visited")


@dataclass(frozen=True)
class IndexRow:
    """One episode on the index page."""

    case_id: str
    status: str
    steps: int
    chosen: str
    metrics: dict[str, float | None]
    """:data:`INDEX_METRICS` of the episode (None: undefined)."""
    check: FrameCheck
    parse_failures: int = 0
    failed_actions: int = 0
    """Steps whose action the engine refused (not visible, unknown room, unparseable)."""
    tokens: int = 0
    """Prompt + completion tokens of the episode."""
    error: str = ""
    """Why an errored episode ended."""


def _check_text(c: FrameCheck) -> str:
    if c.mismatched:
        return f"⚠ {len(c.mismatched)} of {c.checked} frames differ"
    if c.checked:
        return f"✓ {c.checked} frames match"
    return "not checked"


def _cell(value: Any) -> str:
    """A cell sorted by ``data-v`` (numbers as numbers; n/a last either way)."""
    if value is None:
        return '<td data-v="">n/a</td>'
    if isinstance(value, bool):
        return f'<td data-v="{int(value)}">{"yes" if value else "no"}</td>'
    if isinstance(value, int | float):
        shown = f"{value:.3g}" if isinstance(value, float) else f"{value:,}"
        return f'<td data-v="{value}">{shown}</td>'
    return f"<td>{html.escape(str(value))}</td>"


def index_page(rows: Sequence[IndexRow]) -> str:
    """The index of every episode page written; a click on a column header sorts by it.

    :param rows: One :class:`IndexRow` per episode page.
    :returns: The HTML text.
    """
    e = html.escape
    header = [
        "episode",
        "status",
        "steps",
        "chosen room",
        *INDEX_METRICS,
        "parse failures",
        "failed actions",
        "tokens",
        "error",
        "frames vs cassette",
    ]
    body = ""
    for r in rows:
        cells = [
            r.status,
            r.steps,
            r.chosen,
            *(r.metrics.get(m) for m in INDEX_METRICS),
            r.parse_failures,
            r.failed_actions,
            r.tokens,
            r.error,
            _check_text(r.check),
        ]
        link = f'<td><a href="{e(r.case_id)}.html">{e(r.case_id)}</a></td>'
        body += f"<tr>{link}{''.join(map(_cell, cells))}</tr>"
    heads = "".join(f'<th title="sort">{e(h)}</th>' for h in header)
    return f"""<!DOCTYPE html>
<html lang="en"><head><meta charset="utf-8"><title>EMRD episodes</title>
<style>{_asset("page.css")}</style></head><body><h1>EMRD episodes</h1>
<p class="cap">Click a column to sort by it (again: the other way).</p>
<table id="index"><thead><tr>{heads}</tr></thead><tbody>{body}</tbody></table>
<script>{_asset("index.js")}</script></body></html>
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
        images[0].save(
            buffer, format="GIF", save_all=True, append_images=images[1:], duration=ms, loop=0
        )
    return buffer.getvalue()
