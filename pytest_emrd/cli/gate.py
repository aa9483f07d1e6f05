"""``emrd gate RUN_DIR... [--thresholds FILE] [--models FILE]``: gates over run directories.

Evaluates ``thresholds.yaml`` over the episodes of one or several run directories (e.g. the
shards of a CI matrix) with the same cells and verdicts as one ``pytest benchmarks`` run.
Shards must form complete sets unless ``--allow-partial`` is given. Under GitHub Actions
(``$GITHUB_STEP_SUMMARY``) the run's Markdown summary is appended to the step summary. Exit
status: 0 when every gate passes, 1 when one is broken, 2 on a usage error.
"""

from __future__ import annotations

import argparse
import json
import os
import sys
from pathlib import Path

HELP = "evaluate thresholds.yaml over one or more run directories"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("run_dirs", nargs="+", type=Path, metavar="RUN_DIR", help="run directories")
    p.add_argument(
        "--thresholds",
        type=Path,
        default=Path("thresholds.yaml"),
        help="gates file (default: ./thresholds.yaml)",
    )
    p.add_argument("--models", type=Path, help="user model registry YAML")
    p.add_argument("--json", action="store_true", help="print the verdicts as one JSON list")
    p.add_argument(
        "--jobs",
        type=int,
        metavar="J",
        help="processes decoding and measuring the episodes (default: every available core)",
    )
    p.add_argument(
        "--allow-partial",
        action="store_true",
        help="gate an incomplete or duplicated set of shards (the problems go to stderr)",
    )


def run(args: argparse.Namespace) -> int:
    from pytest_emrd.agent import load_registry
    from pytest_emrd.cli import check_run_dirs
    from pytest_emrd.errors import ConfigError, check_positive_int
    from pytest_emrd.gate import evaluate_all, gate_tables, load_thresholds, usage_table
    from pytest_emrd.metrics import GATE_METRICS
    from pytest_emrd.report import registry_prices
    from pytest_emrd.run import (
        EpisodeSummary,
        check_shard_set,
        load_run_episodes,
        measure_episodes,
        usage_rows,
    )

    if args.jobs is not None:
        check_positive_int("--jobs", args.jobs)
    check_run_dirs(args.run_dirs)
    for problem in check_shard_set(args.run_dirs, allow_partial=args.allow_partial):
        print(f"emrd gate: warning: partial shard set: {problem}", file=sys.stderr)
    registry = load_registry(args.models)
    if not args.thresholds.exists():
        raise ConfigError(
            f"--thresholds {args.thresholds} does not exist, so no gate ran; start one from "
            f"these runs: emrd thresholds {' '.join(map(str, args.run_dirs))} --out "
            f"{args.thresholds}"
        )
    thresholds = load_thresholds(args.thresholds, registry=registry, metrics=GATE_METRICS)
    stored = load_run_episodes(args.run_dirs)
    metrics = measure_episodes(stored, args.jobs)
    run_dirs = {s.head.spec.case_id: str(Path(s.source).parent.parent) for s in stored}
    verdicts = evaluate_all(metrics, thresholds, GATE_METRICS, run_dir_of=run_dirs.__getitem__)
    prices = registry_prices(registry, {s.head.spec.model for s in stored})
    if os.environ.get("GITHUB_STEP_SUMMARY"):
        from pytest_emrd.report import append_step_summary, step_summary_markdown

        append_step_summary(
            step_summary_markdown(
                stored,
                verdicts,
                thresholds_source=str(args.thresholds),
                episode_metrics=metrics,
                prices=prices,
            )
        )
    if args.json:
        print(json.dumps([v.to_dict() for v in verdicts]))
    else:
        print(f"{len(stored)} episodes from {len(args.run_dirs)} run director(ies)")
        print("\n".join(gate_tables(verdicts)) or "no gate applies to these episodes")
        priced = ((s, prices.get(s.head.spec.model, (None, None))) for s in stored)
        summaries = [
            EpisodeSummary.of(s, price_in=p_in, price_out=p_out) for s, (p_in, p_out) in priced
        ]
        print("tokens per model:", *usage_table(usage_rows(summaries)), sep="\n")
    return 0 if all(v.passed for v in verdicts) else 1
