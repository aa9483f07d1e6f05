"""``emrd view RUN_DIR [EPISODE...] [--out DIR] [--cassettes DIR] [--gif]``: episode pages.

Writes a self-contained ``<case_id>.html`` per episode (``#step=N`` opens step N), and
``index.html``; with ``--gif`` also ``<case_id>.gif``. EPISODE is a case id or a shell
pattern (default: every episode). Frames are re-rendered and checked against the digests in
the cassettes under ``--cassettes`` (default ``./cassettes`` when it exists).
"""

from __future__ import annotations

import argparse
import fnmatch
from pathlib import Path

from pytest_emrd.errors import ConfigError

_DEFAULT_CASSETTES = Path("cassettes")


HELP = "HTML pages to step through episodes of a run"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("run_dir", type=Path, metavar="RUN_DIR", help="run directory")
    p.add_argument(
        "episodes",
        nargs="*",
        metavar="EPISODE",
        help="case ids or shell patterns (default: every episode)",
    )
    p.add_argument("--out", type=Path, help="output folder (default RUN_DIR/view)")
    p.add_argument(
        "--cassettes",
        type=Path,
        help="cassette folder the frames are checked against (default ./cassettes)",
    )
    p.add_argument("--gif", action="store_true", help="also write an animated GIF per episode")


def run(args: argparse.Namespace) -> int:
    from pytest_emrd._files import check_inside, write_bytes_atomic
    from pytest_emrd._scrub import scrub_bytes
    from pytest_emrd.cli import check_run_dirs
    from pytest_emrd.run import load_run_dirs
    from pytest_emrd.view import index_page, render_episode

    check_run_dirs([args.run_dir])
    trajectories = sorted(load_run_dirs([args.run_dir]), key=lambda t: t.spec.case_id)
    if args.episodes:
        chosen = [
            t
            for t in trajectories
            if any(fnmatch.fnmatchcase(t.spec.case_id, p) for p in args.episodes)
        ]
        if not chosen:
            raise ConfigError(
                f"episodes={args.episodes} match no episode of {args.run_dir} (it holds e.g. "
                f"{', '.join(t.spec.case_id for t in trajectories[:3])}); give case ids or "
                "shell patterns such as '*-kitchen-*'."
            )
        trajectories = chosen
    cassettes = args.cassettes
    if cassettes is None and _DEFAULT_CASSETTES.is_dir():
        cassettes = _DEFAULT_CASSETTES
    out = args.out or args.run_dir / "view"
    out.mkdir(parents=True, exist_ok=True)
    rows = []
    for t in trajectories:
        view = render_episode(t, cassettes=cassettes, gif=args.gif)
        page = check_inside(out, out / f"{t.spec.case_id}.html", what="page")  # a stored name
        write_bytes_atomic(page, scrub_bytes(view.html.encode()))
        if view.gif:
            write_bytes_atomic(page.with_suffix(".gif"), view.gif)
        check = view.row.check
        status = (
            f"{len(check.mismatched)} of {check.checked} frames DIFFER from the cassette"
            if check.mismatched
            else f"{check.checked} frames match the cassette"
            if check.checked
            else f"frames not checked ({check.note})"
        )
        print(f"{page} ({page.stat().st_size / 1e6:.2f} MB): {status}")
        rows.append(view.row)
    index = out / "index.html"
    write_bytes_atomic(index, scrub_bytes(index_page(rows).encode()))
    print(index)
    return 0
