"""``emrd view``: frames re-rendered and checked, per-step map and metrics, pages and GIF."""

from __future__ import annotations

import dataclasses
import io
import re
from pathlib import Path

import pytest
from PIL import Image

from pytest_emrd.cli import main
from pytest_emrd.episode import run_episode
from pytest_emrd.metrics import episode_metrics
from pytest_emrd.run import StoredEpisode
from pytest_emrd.trajectory import Trajectory
from pytest_emrd.view import (
    Recorded,
    episode_data,
    episode_page,
    recorded_digests,
    render_episode,
    replay_frames,
)


def test_re_rendered_frames_match_the_committed_cassette(episode, cassettes: Path) -> None:
    frames = replay_frames(episode).frames
    recorded = recorded_digests(episode, cassettes)
    assert recorded.note is None and len(frames) == len(episode.steps) == len(recorded.digests)
    assert [f.digest for f in frames] == list(recorded.digests)


def test_a_frame_that_differs_is_flagged_on_its_step(episode: Trajectory, cassettes) -> None:
    frames = replay_frames(episode).frames
    digests = list(recorded_digests(episode, cassettes).digests)
    digests[2] = "pixels:" + "0" * 64
    data, check = episode_data(episode, frames, Recorded(tuple(digests)))
    assert check.mismatched == (3,) and check.checked == len(frames)
    assert [s["frame_ok"] for s in data["steps"][:4]] == [True, True, False, True]
    assert "differ from the recorded digest (steps 3)" in data["notes"][0]


def test_without_a_cassette_frames_are_shown_unchecked(episode, tmp_path: Path) -> None:
    recorded = recorded_digests(episode, tmp_path)
    assert recorded.digests == () and "frames not checked" in recorded.note
    data, check = episode_data(episode, replay_frames(episode).frames, recorded)
    assert check.checked == 0 and {s["frame_ok"] for s in data["steps"]} == {None}
    assert any("no cassette at" in n for n in data["notes"])


def test_text_modality_says_the_model_saw_no_frame(episode, cassettes) -> None:
    text = dataclasses.replace(episode, spec=dataclasses.replace(episode.spec, modality="text"))
    assert "the model was shown no frame" in (recorded_digests(text, cassettes).note or "")


def test_last_step_metrics_are_the_episode_metrics(episode: Trajectory) -> None:
    data, _ = episode_data(episode, (), Recorded(()))
    m = episode_metrics(episode)
    last = data["steps"][-1]
    assert last["coverage"] == pytest.approx(m.aec, abs=1e-3)
    assert last["pa"] == pytest.approx(m.pa, abs=1e-3)
    assert [s["tbs"] for s in data["steps"]] == pytest.approx(list(m.tbs), abs=1e-3)
    # scout maps in the spawn frame exactly: aligned entries sit on their objects
    truth = {o.object_id: (o.x, o.z) for o in episode.ground_truth.objects}
    for label, x, z, oid in last["map"]:
        assert oid is not None and (x, z) == pytest.approx(truth[oid], abs=0.05), label


def test_the_plan_is_the_offices_north_up_whatever_the_spawn(episode: Trajectory) -> None:
    from pytest_emrd.episode import run_episode
    from pytest_emrd.trajectory import EpisodeSpec
    from pytest_emrd.world import paper_office

    other = run_episode(EpisodeSpec("scout", "baseline", "kitchen", 0, modality="both"))
    plans = []
    for traj in (episode, other):
        replay = replay_frames(traj)
        data, _ = episode_data(traj, replay.frames, Recorded(()), spawn=replay.spawn)
        assert data["plan_frame"] == "the office's frame, north up"
        office = {o[0]: (o[3], o[4]) for o in data["objects"]}
        plans.append(office)
        for label, x, z, oid in data["steps"][-1]["map"]:  # aligned entries sit on their objects
            assert oid is not None and (x, z) == pytest.approx(office[oid], abs=0.05), label
        first = data["steps"][0]
        assert first["at"][:2] == pytest.approx((replay.spawn.x, replay.spawn.z), abs=1e-3)
        assert first["at"][2] == replay.spawn.heading % 360.0 and first["pose"][2] == 0.0
    assert plans[0] == plans[1]  # two spawns, one office: the same plan
    world = {o.object_id: (o.x, o.z) for o in paper_office().objects}
    assert all(plans[0][k] == pytest.approx(world[k], abs=1e-3) for k in plans[0])


def test_page_is_self_contained_and_small(episode: Trajectory, cassettes) -> None:
    view = render_episode(episode, cassettes=cassettes, gif=True)
    html = view.html
    assert not re.search(r"""(src|href)=["']?(https?:|//)""", html)
    assert html.count("<script>") == 1 and "</script>" not in html.split("<script>")[1][:-30]
    per_step = len(html.encode()) / len(episode.steps)
    assert per_step < 60_000, per_step  # < 3 MB for a 50-step episode
    gif = Image.open(io.BytesIO(view.gif or b""))
    assert gif.format == "GIF" and gif.n_frames == len(episode.steps)
    assert view.row.check.checked == len(episode.steps) and not view.row.check.mismatched


def test_script_text_cannot_close_the_script(episode: Trajectory) -> None:
    last = episode.steps[-1]
    evil = dataclasses.replace(last, raw_reply="</script><script>alert(1)</script>")
    traj = dataclasses.replace(episode, steps=(*episode.steps[:-1], evil))
    data, _ = episode_data(traj, (), Recorded(()))
    assert "</script><script>" not in episode_page(data, ())


def test_cli_writes_pages_index_and_gif(episode, cassettes, tmp_path: Path, capsys) -> None:
    run = tmp_path / "run"
    (run / "episodes").mkdir(parents=True)
    stored = StoredEpisode.of(episode, session="t", recorded=False, frame_drift=0, seconds=0.1)
    (run / "episodes" / f"{episode.spec.case_id}.json").write_bytes(stored.to_json())
    out = tmp_path / "view"
    argv = ["view", str(run), "*-office-ep00", "--out", str(out), "--gif",
            "--cassettes", str(cassettes)]  # fmt: skip
    assert main(argv) == 0
    assert {p.name for p in out.iterdir()} == {
        "index.html",
        f"{episode.spec.case_id}.html",
        f"{episode.spec.case_id}.gif",
    }
    assert f"{len(episode.steps)} frames match the cassette" in capsys.readouterr().out
    assert main(["view", str(run), "*-kitchen-*"]) == 2
    assert "match no episode" in capsys.readouterr().err


def test_each_step_is_laid_out_as_the_model_lived_it(episode: Trajectory) -> None:
    """Frame and pose before the action, the request (system prompt, the step's text, the
    window's frames), reply and action with tokens and latency, then the engine's feedback
    labelled as the result, with where the agent stood after it."""
    from pytest_emrd.agent import HISTORY_TURNS

    replay = replay_frames(episode)
    data, _ = episode_data(episode, replay.frames, Recorded(()), None, replay.spawn,
                           replay.system)  # fmt: skip
    assert data["system"] == replay.system and "REPLY FORMAT" in data["system"]
    steps = data["steps"]
    first, fifth, twelfth = steps[0], steps[4], steps[11]
    assert first["window"] == [0] and fifth["window"] == [0, 1, 2, 3, 4]
    assert twelfth["window"] == list(range(12 - HISTORY_TURNS, 12))
    # the text shown with frame t carries the feedback of action t-1, never of action t
    assert episode.steps[3].feedback in fifth["prompt"]
    assert fifth["feedback"] == episode.steps[4].feedback
    assert fifth["after"].startswith(episode.steps[5].room)
    assert fifth["tokens"] == [episode.steps[4].usage.prompt_tokens,
                               episode.steps[4].usage.completion_tokens]  # fmt: skip
    assert fifth["latency"] == episode.steps[4].latency_s
    assert all(s["latency"] is not None and s["latency"] >= 0 for s in steps), "run live"
    html = episode_page(data, replay.frames)
    order = ["1 · Before the action", "2 · The request", "3 · Reply and action",
             "4 · Result: the engine's feedback on this action"]  # fmt: skip
    positions = [html.index(h) for h in order]
    assert positions == sorted(positions)
    assert "<details><summary>system prompt (the same at every step)</summary>" in html


def test_latency_is_recorded_live_and_not_compared() -> None:
    import dataclasses

    from pytest_emrd.episode import run_episode
    from pytest_emrd.trajectory import EpisodeSpec

    spec = EpisodeSpec("scout", "baseline", "office", 1, modality="both", max_steps=3)
    live = run_episode(spec)
    assert all(s.latency_s is not None and 0 <= s.latency_s < 30 for s in live.steps)
    blank = dataclasses.replace(live, steps=tuple(
        dataclasses.replace(s, latency_s=None) for s in live.steps))  # fmt: skip
    assert blank == live, "a replay (no latency) equals its recording"
    from pytest_emrd.trajectory import Trajectory as T

    assert T.from_dict(live.to_dict()).steps[0].latency_s == live.steps[0].latency_s


def test_a_replayed_step_shows_the_latency_recorded_with_its_reply(episode) -> None:
    replayed = [dataclasses.replace(s, latency_s=None) for s in episode.steps]
    replay = dataclasses.replace(episode, steps=tuple(replayed))
    steps = episode_data(replay, [], Recorded((), latencies=(1.25, None)))[0]["steps"]
    assert steps[0]["latency"] is None and steps[0]["recorded_latency"] == 1.25
    assert steps[1]["recorded_latency"] is None and steps[2]["recorded_latency"] is None


def test_a_cassette_recorded_again_is_not_called_a_world_change(episode, cassettes) -> None:
    """ep00's cassette against the trajectory of another episode under ep00's name: its replies
    differ, so the cassette was recorded again after this run; the frames are not checked."""
    other = run_episode(dataclasses.replace(episode.spec, episode=1))
    rerun = dataclasses.replace(other, spec=episode.spec)
    recorded = recorded_digests(rerun, cassettes)
    assert recorded.digests == () and "was recorded again after this episode ran" in recorded.note
    assert recorded_digests(episode, cassettes).note is None
