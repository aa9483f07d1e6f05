"""``emrd report RUN_DIR... [--out DIR] [--format md,html,json]``,
``emrd report --compare RUN_A RUN_B [--compare-models A B]`` and
``emrd report RUN_DIR... --compare-models A B``: the paper's tables and figures from run
directories, or a paired comparison of two runs or two models.

Several run directories (shards) make one report; the gate section uses ``--thresholds`` or
``./thresholds.yaml``. A comparison writes ``compare.*`` into ``--out`` (else prints the
Markdown). Exit status 0, or 2 on a usage error.
"""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pytest_emrd.errors import ConfigError, check_choice

_DEFAULT_THRESHOLDS = Path("thresholds.yaml")


HELP = "tables and figures of one or more run directories"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("run_dirs", nargs="*", type=Path, metavar="RUN_DIR", help="run directories")
    p.add_argument(
        "--compare",
        nargs=2,
        type=Path,
        metavar=("RUN_A", "RUN_B"),
        help="compare two run directories metric by metric (paired by episode, B - A, "
        "bootstrap CI, Holm-corrected verdict)",
    )
    p.add_argument(
        "--compare-models",
        nargs=2,
        metavar=("MODEL_A", "MODEL_B"),
        help="compare two model names: within RUN_DIR..., or model A of RUN_A with model B "
        "of RUN_B together with --compare",
    )
    p.add_argument("--out", type=Path, help="output folder (default: FIRST_RUN_DIR/report)")
    p.add_argument(
        "--format", default="md,html,json", help="comma-separated: md, html, json (default: all)"
    )
    p.add_argument(
        "--thresholds",
        type=Path,
        help="gates file for the gate section (default: ./thresholds.yaml if it exists)",
    )
    p.add_argument("--models", type=Path, help="user model registry YAML")
    p.add_argument(
        "--episode",
        metavar="CASE_ID",
        help="episode the map figure shows, e.g. scout-low_light-kitchen-ep07 (default: the "
        "first baseline episode with a non-empty map)",
    )
    p.add_argument("--seed", type=int, default=0, help="bootstrap seed of --compare (default 0)")


def run(args: argparse.Namespace) -> int:
    from pytest_emrd.report import check_formats

    formats = check_formats(f.strip() for f in args.format.split(",") if f.strip())
    if bool(args.compare) == bool(args.run_dirs):
        raise ConfigError(
            f"run_dirs={[str(p) for p in args.run_dirs]} compare={args.compare}: give either "
            "RUN_DIR... or --compare RUN_A RUN_B, not both and not neither."
        )
    if args.compare or args.compare_models:
        return _compare(args, formats)
    return _report(args, formats)


def _report(args: argparse.Namespace, formats: list[str]) -> int:
    from pytest_emrd._fork import available_cores
    from pytest_emrd.agent import load_registry
    from pytest_emrd.cli import check_run_dirs
    from pytest_emrd.gate import evaluate_all, load_thresholds
    from pytest_emrd.metrics import GATE_METRICS
    from pytest_emrd.report import build_report, registry_prices, write_report
    from pytest_emrd.run import load_run_episodes, measure_episodes

    check_run_dirs(args.run_dirs)
    episodes = load_run_episodes(args.run_dirs)
    # each episode measured once (on every core), for the gates and the report, not kept
    metrics = measure_episodes(episodes)
    registry = load_registry(args.models)
    thresholds_path = args.thresholds
    if thresholds_path is None and _DEFAULT_THRESHOLDS.is_file():
        thresholds_path = _DEFAULT_THRESHOLDS
    verdicts, source = [], None
    if thresholds_path is not None:
        thresholds = load_thresholds(thresholds_path, registry=registry, metrics=GATE_METRICS)
        verdicts = evaluate_all(metrics, thresholds, GATE_METRICS)  # cells by each one's spec
        source = str(thresholds_path)
    prices = registry_prices(registry, {e.head.spec.model for e in episodes})
    # two processes where there are two cores: the map alignment beside the tables, then figures
    processes = min(2, available_cores())
    report = build_report(
        episodes,
        verdicts=verdicts,
        thresholds_source=source,
        prices=prices,
        episode_metrics=metrics,
        episode=args.episode,
        processes=processes,
    )
    written = write_report(
        report, args.out or args.run_dirs[0] / "report", formats, processes=processes
    )
    print(f"{len(episodes)} episodes from {len(args.run_dirs)} run director(ies)")
    for note in report.missing:
        print(f"note: {note}")
    for path in written:
        print(path)
    return 0


def _compare(args: argparse.Namespace, formats: list[str]) -> int:
    from pytest_emrd.report import compare_lines, compare_runs, render_comparison, write_files
    from pytest_emrd.run import load_run_dirs

    if args.compare:
        run_a, run_b = args.compare
        trajectories_a, trajectories_b = load_run_dirs([run_a]), load_run_dirs([run_b])
        names = (str(run_a), str(run_b))
    else:
        trajectories_a = trajectories_b = load_run_dirs(args.run_dirs)
        names = (" ".join(map(str, args.run_dirs)),) * 2
    models = tuple(args.compare_models) if args.compare_models else None
    for name, trajectories in zip(models or (), (trajectories_a, trajectories_b), strict=False):
        held = sorted({t.spec.model for t in trajectories})
        check_choice("compare-models", name, held, hint="Name a model the run holds.")
    comparison = compare_runs(
        trajectories_a, trajectories_b, names=names, models=models, rng_seed=args.seed
    )
    if args.out is None:
        sys.stdout.write(render_comparison(comparison, ["md"])["compare.md"].decode())
        return 0
    print(*compare_lines(comparison), sep="\n")
    for path in write_files(render_comparison(comparison, formats), args.out):
        print(path)
    return 0
