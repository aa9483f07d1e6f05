"""Cassette paths: the builtin tree stays where the committed cassettes are; other backends
get their own tree, and the record command names the backend."""

from __future__ import annotations

from pathlib import Path

import pytest

from pytest_emrd.cassette import cassette_path, record_command
from pytest_emrd.trajectory import EpisodeSpec

ROOT = Path("cassettes")


@pytest.mark.parametrize(
    ("spec", "expected"),
    [
        (
            EpisodeSpec("scout", "low_light", "kitchen", 7),
            "cassettes/scout/low_light/default/kitchen/ep07.json.xz",
        ),
        (
            EpisodeSpec("gemini", "texture", "office", 12, variant="B3", backend="ai2thor"),
            "cassettes/ai2thor/gemini/texture/B3/office/ep12.json.xz",
        ),
        (
            EpisodeSpec("ai2thor", "baseline", "entrance", 0),
            "cassettes/ai2thor/baseline/default/entrance/ep00.json.xz",
        ),
    ],
    ids=["builtin", "ai2thor", "builtin-model-named-like-a-backend"],
)
def test_cassette_path(spec, expected):
    assert cassette_path(ROOT, spec).as_posix() == expected


def test_backends_never_share_a_cassette():
    specs = [
        EpisodeSpec(model, "baseline", "office", 0, backend=backend)
        for model in ("scout", "ai2thor", "baseline")
        for backend in ("builtin", "ai2thor")
    ]
    assert len({cassette_path(ROOT, s) for s in specs}) == len(specs)


def test_the_record_command_names_a_non_builtin_backend():
    spec = EpisodeSpec("gemini", "baseline", "office", 3, backend="ai2thor")
    command = record_command(spec, record_mode="once")
    assert "--emrd-backend=ai2thor" in command and "--emrd-episodes=4" in command
    assert "--emrd-backend" not in record_command(
        EpisodeSpec("gemini", "baseline", "office", 3), record_mode="once"
    )
