"""The episode viewer: one self-contained HTML page per episode of a run (``emrd view``).

:func:`render_episode` re-renders the frames a model saw (:func:`replay_frames`), checks them
against the cassette's digests (:func:`recorded_digests`) and returns the page, its index row
and, optionally, a GIF. Writing files is the caller's job (:mod:`pytest_emrd.cli.view`).
"""

from __future__ import annotations

from dataclasses import dataclass
from pathlib import Path

from pytest_emrd.errors import EmrdError
from pytest_emrd.trajectory import Trajectory
from pytest_emrd.view._page import IndexRow, episode_data, episode_gif, episode_page, index_page
from pytest_emrd.view._replay import Recorded, recorded_digests, replay_frames

__all__ = [
    "EpisodeView",
    "Recorded",
    "episode_data",
    "episode_page",
    "index_page",
    "recorded_digests",
    "render_episode",
    "replay_frames",
]


@dataclass(frozen=True)
class EpisodeView:
    """One episode's page (and GIF when asked for) and its row of the index."""

    html: str
    gif: bytes | None
    row: IndexRow


def render_episode(traj: Trajectory, *, cassettes: Path | None, gif: bool = False) -> EpisodeView:
    """Re-render, check and lay out one episode (see the module docstring); a backend this
    machine cannot run leaves the frames out and says why."""
    try:
        replay, note = replay_frames(traj), None
    except EmrdError as exc:
        replay, note = None, f"frames not re-rendered: {exc}"
    frames = replay.frames if replay else ()
    spawn = replay.spawn if replay else None
    system = replay.system if replay else None
    data, check = episode_data(traj, frames, recorded_digests(traj, cassettes), note, spawn, system)
    last = data["steps"][-1] if data["steps"] else {"coverage": None, "pa": None}
    chosen = traj.chosen_room or (traj.chosen_room_raw and f"{traj.chosen_room_raw!r}") or "-"
    row = IndexRow(traj.spec.case_id, traj.status, len(traj.steps), chosen,
                   last["coverage"], last["pa"], check)  # fmt: skip
    return EpisodeView(episode_page(data, frames), episode_gif(data, frames) if gif else None, row)
