"""Where an episode's cassette lives, and the command that (re-)records it."""

from __future__ import annotations

import shlex
from pathlib import Path

from pytest_emrd.trajectory import EpisodeSpec


def cassette_path(root: Path, spec: EpisodeSpec) -> Path:
    """``<root>/<model>/<condition>/<variant>/<spawn>/ep<NN>.yaml.gz`` on the builtin world,
    ``<root>/<backend>/<model>/...`` on any other backend (``cassettes/ai2thor/gemini/...``).

    The builtin path carries no backend so the committed cassettes keep their place; the
    other backends get their own tree, so a THOR recording never answers a builtin run (or
    the reverse) even when a model happens to be named like a backend.
    """
    base = root if spec.backend == "builtin" else root / spec.backend
    return (
        base
        / spec.model
        / spec.condition
        / spec.variant
        / spec.spawn
        / f"ep{spec.episode:02d}.yaml.gz"
    )


def record_command(spec: EpisodeSpec, *, record_mode: str, cassettes: Path | None = None) -> str:
    """The exact ``pytest`` command that records (``once``) or re-records (``all``) one episode."""
    args = [
        "pytest",
        "benchmarks",
        f"--emrd-model={spec.model}",
        f"--emrd-condition={spec.condition}",
        f"--emrd-spawn={spec.spawn}",
        f"--emrd-episodes={spec.episode + 1}",
    ]
    if spec.variant != "default":
        args.append(f"--emrd-variant={spec.variant}")
    if spec.backend != "builtin":
        args.append(f"--emrd-backend={spec.backend}")
    if cassettes is not None:
        args.append(f"--emrd-cassettes={cassettes}")
    args += [f"--emrd-record-mode={record_mode}", "-k", f"test_episode and {spec.case_id}"]
    return shlex.join(args)
