"""The episode viewer: one self-contained HTML page per episode of a run (``emrd view``).

:func:`render_episode` re-renders the frames a model saw (:func:`replay_frames`), checks them
against the cassette's digests (:func:`recorded_digests`) and returns the page, its index row
and, optionally, a GIF. Writing files is the caller's job (:mod:`pytest_emrd.cli.view`).

Cassettes keep a frame's pixel digest, never its image. The viewer rebuilds the spec's world
through the episode loop's own :func:`~pytest_emrd.episode.start_world`, replays the recorded
actions as the loop did (:func:`~pytest_emrd.episode.world_action`), and compares each
re-rendered frame's digest with the one the cassette recorded for that step.
"""

from __future__ import annotations

import json
from collections.abc import Iterator
from dataclasses import dataclass
from pathlib import Path
from typing import Any

from pytest_emrd.agent import build_system_prompt
from pytest_emrd.cassette import DIGEST, LATENCY, FormatError, found_cassette, read_cassette
from pytest_emrd.episode import build_simulator, start_world, user_turn, world_action
from pytest_emrd.errors import ConfigError, EmrdError
from pytest_emrd.trajectory import Trajectory
from pytest_emrd.view._page import (
    Frame,
    FrameCheck,
    IndexRow,
    Recorded,
    episode_data,
    episode_gif,
    episode_page,
    index_page,
)
from pytest_emrd.world import WorldPose

__all__ = [
    "EpisodeView",
    "FrameCheck",
    "IndexRow",
    "Recorded",
    "episode_data",
    "episode_page",
    "index_page",
    "recorded_digests",
    "render_episode",
    "replay_frames",
]


@dataclass(frozen=True)
class Replay:
    """The frames of an episode re-rendered, and where it started in the office."""

    frames: tuple[Frame, ...]
    spawn: WorldPose
    """The spawn pose in the office's own frame (the page draws the plan in it, north up)."""
    system: str = ""
    """The system prompt the episode loop sends for this spec (the same for every step)."""


def replay_frames(traj: Trajectory) -> Replay:
    """The frame and user text shown at each step of ``traj``, the system prompt and the spawn
    pose; :class:`EmrdError` when the spec's backend cannot be built here (AI2-THOR without
    its extra or a GPU).

    :param traj: The episode to replay.
    :returns: The :class:`Replay`.
    """
    sim = build_simulator(traj.spec.backend)
    try:
        spec = traj.spec
        layout, obs = start_world(spec, sim)
        spawn = sim.spawn_pose
        system = build_system_prompt(
            layout.inventory(), spec.variant, modality=spec.modality, max_steps=spec.max_steps
        )
        frames = []
        for step in traj.steps:
            text = user_turn(spec, step.index, obs, replay=True).text
            frames.append(Frame(obs.jpeg, f"pixels:{obs.frame_digest}", text))
            obs = sim.step(world_action(step.action, spec.variant)[0])
        return Replay(tuple(frames), spawn, system)
    finally:
        sim.close()


def _strings(node: Any) -> Iterator[str]:
    if isinstance(node, dict | list):
        for value in node.values() if isinstance(node, dict) else node:
            yield from _strings(value)
    elif isinstance(node, str):
        yield node


def _json(body: Any) -> Any:
    try:
        return json.loads(body or b"null")
    except ValueError:
        return None


def recorded_digests(traj: Trajectory, cassettes: Path | None) -> Recorded:
    """Frame digests of ``traj``'s cassette under ``cassettes``: the newest image of each
    request is the frame of that step (a history window carries older ones before it).

    :param traj: The episode.
    :param cassettes: The cassette folder; None when there is none.
    :returns: The :class:`Recorded` digests, or a note why there are none.
    """
    if traj.spec.modality == "text":
        return Recorded(
            (),
            "text modality: the model was shown no frame; the frames are what "
            "its camera would have shown",
        )
    if cassettes is None:
        return Recorded((), "no cassette folder given (--cassettes): frames not checked")
    path = found_cassette(cassettes, traj.spec)
    try:
        data, _ = read_cassette(path, root=cassettes)
    except FileNotFoundError:
        return Recorded((), f"no cassette at {path}: frames not checked")
    except (FormatError, ConfigError) as exc:
        return Recorded((), f"{path} is not a readable cassette ({exc}): frames not checked")
    if data.protocol != traj.protocol:
        return Recorded(
            (),
            f"{path} was recorded under protocol {data.protocol}, the episode "
            f"ran under {traj.protocol}: frames not checked",
        )
    replies = (_strings(_json(r["body"]["string"])) for r in data.responses)
    pairs = zip(traj.steps, replies, strict=False)
    changed = [s.index for s, r in pairs if s.raw_reply and s.raw_reply not in r]
    if changed:
        again = (
            f"{path} was recorded again after this episode ran (its reply to step {changed[0]} "
            "is another): frames not checked against it; view the run that recorded it, or "
            "replay this episode again"
        )
        return Recorded((), again)
    digests = []
    for request in data.requests:
        found = [d for d in _strings(_json(request.body)) if DIGEST.match(d)]
        digests.append(found[-1] if found else None)
    note = (
        f"{path} holds {len(digests)} requests for {len(traj.steps)} steps: steps "
        "are checked in order up to the shorter"
        if len(digests) != len(traj.steps)
        else None
    )
    latencies = tuple(r.get(LATENCY) for r in data.responses)
    return Recorded(tuple(digests), note, latencies)


@dataclass(frozen=True)
class EpisodeView:
    """One episode's page (and GIF when asked for) and its row of the index."""

    html: str
    gif: bytes | None
    row: IndexRow


def render_episode(traj: Trajectory, *, cassettes: Path | None, gif: bool = False) -> EpisodeView:
    """Re-render, check and lay out one episode (see the module docstring); a backend this
    machine cannot run leaves the frames out and says why.

    :param traj: The episode.
    :param cassettes: The cassette folder the frames are checked against; None to skip.
    :param gif: Also render an animated GIF.
    :returns: The :class:`EpisodeView`: HTML, GIF and index row.
    """
    try:
        replay = replay_frames(traj)
        frames, spawn, system, note = replay.frames, replay.spawn, replay.system, None
    except EmrdError as exc:
        frames, spawn, system, note = (), None, None, f"frames not re-rendered: {exc}"
    data, check = episode_data(traj, frames, recorded_digests(traj, cassettes), note, spawn, system)
    chosen = traj.chosen_room or (traj.chosen_room_raw and f"{traj.chosen_room_raw!r}") or "-"
    row = IndexRow(
        traj.spec.case_id,
        traj.status,
        len(traj.steps),
        chosen,
        data["metrics"],
        check,
        parse_failures=sum(s.parse_error is not None for s in traj.steps),
        failed_actions=sum(not s.success for s in traj.steps),
        tokens=sum(s.usage.prompt_tokens + s.usage.completion_tokens for s in traj.steps),
        error=traj.error or "",
    )
    return EpisodeView(episode_page(data, frames), episode_gif(data, frames) if gif else None, row)
