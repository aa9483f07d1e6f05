"""The data of one episode page: per step what the model saw, said and did, its map aligned
onto the ground truth, and the metrics at that step (pure).

A step is laid out in the order the model lived it: the frame and pose shown *before* the
action, the request (system prompt, this step's text, the frames of the history window),
the reply and its action (tokens, latency), then the engine's feedback on that action, the
*result*, with where the agent stood after it.

Per step ``t`` the map ``M_t`` is matched by :func:`pytest_emrd.metrics.step_matchings`
(identities carried and revised exactly as every episode metric does), aligned with the report's
:func:`~pytest_emrd.report.align_map` (Procrustes on the matched pairs), and scored
with the metrics' own per-episode terms: coverage ``|K| / |E|`` (:func:`aec_score`),
Positional Accuracy (:func:`positional_accuracy_score`) and ``TBS(t)`` (:func:`episode_metrics`).
"""

from __future__ import annotations

from collections.abc import Callable, Sequence
from dataclasses import dataclass
from typing import Any

from pytest_emrd.agent import HISTORY_TURNS, parse_reply
from pytest_emrd.metrics import (
    aec_score,
    episode_metrics,
    positional_accuracy_score,
    step_matchings,
)
from pytest_emrd.report import align_map
from pytest_emrd.trajectory import Trajectory
from pytest_emrd.view._replay import Frame, Recorded
from pytest_emrd.world import WorldPose, local_to_world


@dataclass(frozen=True)
class FrameCheck:
    """How the re-rendered frames compare with the cassette's digests."""

    checked: int
    mismatched: tuple[int, ...]
    """Steps whose re-rendered frame differs from the recorded one."""
    note: str | None
    """Why some or all steps are not checked."""


def check_frames(
    frames: Sequence[Frame], recorded: Recorded
) -> tuple[list[bool | None], FrameCheck]:
    """Per step: True (digest equal), False (mismatch) or None (not checked)."""
    status: list[bool | None] = []
    for i, frame in enumerate(frames):
        digest = recorded.digests[i] if i < len(recorded.digests) else None
        status.append(None if digest is None else digest == frame.digest)
    bad = tuple(i + 1 for i, s in enumerate(status) if s is False)
    return status, FrameCheck(sum(s is not None for s in status), bad, recorded.note)


def _round(x: float | None, digits: int = 3) -> float | None:
    return None if x is None else round(x, digits)


def _office(spawn: WorldPose | None) -> Callable[[float, float], tuple[float, float]]:
    """Spawn frame -> the office's own frame (north up, the same for every spawn), rounded to
    the millimetre; the identity when the spawn pose is unknown (frames not re-rendered)."""
    if spawn is None:
        return lambda x, z: (round(x, 3), round(z, 3))

    def place(x: float, z: float) -> tuple[float, float]:
        wx, wz = local_to_world(spawn.x, spawn.z, spawn.heading, x, z)
        return round(wx, 3), round(wz, 3)

    return place


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
    """
    place, turn = _office(spawn), spawn.heading if spawn else 0.0
    truth = traj.ground_truth
    g_base = len(truth.discoverable_ids)
    tbs = episode_metrics(traj).tbs
    status, check = check_frames(frames, recorded)
    steps = []
    matchings = step_matchings([s.cognitive_map for s in traj.steps], truth.objects)
    for i, (s, matching) in enumerate(zip(traj.steps, matchings, strict=True)):
        points, rotation, rmse = align_map(s.cognitive_map, matching)
        reply = parse_reply(s.raw_reply)
        after = traj.steps[i + 1] if i + 1 < len(traj.steps) else None
        steps.append({
            "t": s.index, "action": s.action, "success": s.success, "feedback": s.feedback,
            "parse_error": s.parse_error, "observation": reply.observation,
            "dedup": reply.dedup_check, "reasoning": reply.reasoning, "raw": s.raw_reply,
            "pose": [round(s.pose.x, 3), round(s.pose.z, 3), round(s.pose.heading, 1)],
            "at": [*place(s.pose.x, s.pose.z), round((s.pose.heading + turn) % 360.0, 1)],
            "room": s.room, "visible": list(s.visible_ids),
            "map": [[p.label, *place(p.x, p.z), p.object_id] for p in points],
            "rotation": round(rotation, 1), "rmse": _round(rmse),
            "coverage": _round(aec_score(matching, len(truth.objects))),
            "pa": _round(positional_accuracy_score(matching, g_base)),
            "tbs": _round(tbs[i]) if i < len(tbs) else None,
            "frame": i if i < len(frames) else None,
            "frame_ok": status[i] if i < len(status) else None,
            "prompt": frames[i].text or None if i < len(frames) else None,
            "window": [j for j in range(max(0, i - HISTORY_TURNS + 1), i + 1) if j < len(frames)],
            "tokens": [s.usage.prompt_tokens, s.usage.completion_tokens],
            "latency": s.latency_s,
            "after": (f"{after.room} (x={after.pose.x:.2f} z={after.pose.z:.2f} "
                      f"heading={after.pose.heading:.0f}°)" if after else traj.final_room),
        })  # fmt: skip
    notes = [n for n in (note, check.note) if n]
    if check.mismatched:
        notes.insert(0, f"{len(check.mismatched)} re-rendered frame(s) differ from the recorded "
                     f"digest (steps {', '.join(map(str, check.mismatched))}): the world changed "
                     "since recording; those frames are not what the model saw")  # fmt: skip
    data = {
        "case_id": traj.spec.case_id, "model": traj.spec.model,
        "condition": traj.spec.condition, "variant": traj.spec.variant,
        "spawn": traj.spec.spawn, "episode": traj.spec.episode, "status": traj.status,
        "protocol": traj.protocol, "chosen_room": traj.chosen_room,
        "chosen_raw": traj.chosen_room_raw, "rationale": traj.rationale, "error": traj.error,
        "final_room": traj.final_room, "notes": notes, "system": system,
        "plan_frame": "the office's frame, north up" if spawn else "the spawn frame",
        "rooms": [{"name": r.name, "polygon": [list(place(*p)) for p in r.polygon]}
                  for r in truth.rooms],
        "objects": [[o.object_id, o.object_type, o.category, *place(o.x, o.z)]
                    for o in truth.objects],
        "steps": steps,
    }  # fmt: skip
    return data, check
