"""``emrd check --emrd-model NAME [...]``: preflight before a live grid.

Takes the grid options of ``pytest benchmarks`` (``--emrd-model``, ``--emrd-condition``,
``--emrd-spawn``, ``--emrd-episodes``, ``--emrd-variant``, ``--emrd-modality``,
``--emrd-models``), so the same flags check what a run would do. For each model: key,
endpoint, one real probe request (a full history window of real frames), the reply read in
the EMRD protocol, context length and image limit, and the tokens and cost of its episodes.
``--no-probe`` checks the key and estimates without touching the network. Exit status: 0
when every check passes, 1 when one fails, 2 on a usage error.
"""

from __future__ import annotations

import argparse
import json
from pathlib import Path

from pytest_emrd.run import OPTIONS

#: The ``--emrd-*`` options that shape what a live run sends.
GRID_OPTIONS = ("model", "condition", "spawn", "episodes", "variant", "modality", "models")


HELP = "preflight a model before a live run: key, endpoint, probe, context, cost"
DESCRIPTION = __doc__.split("\n\n")[1]


def add_arguments(p: argparse.ArgumentParser) -> None:
    for option in (o for o in OPTIONS if o.name in GRID_OPTIONS):
        p.add_argument(option.flag, **option.argparse_kwargs(option.name))
    p.add_argument("--no-probe", action="store_true", help="no network: key and estimate only")
    p.add_argument("--json", action="store_true", help="print the reports as one JSON list")


def run(args: argparse.Namespace) -> int:
    from pytest_emrd._scrub import scrub
    from pytest_emrd.agent import load_registry
    from pytest_emrd.preflight import preflight
    from pytest_emrd.run import episode_specs, resolve_settings

    cli = {name: getattr(args, name) for name in GRID_OPTIONS}
    settings = resolve_settings(cli, {}, rootdir=Path.cwd())
    registry = load_registry(settings.models_file)
    specs = episode_specs(settings, lambda model: str(registry.get(model).modality))
    reports = []
    for model in settings.models:
        mine = [s for s in specs if s.model == model]
        report = preflight(
            registry.get(model), mine[0], episodes=len(mine), probe=not args.no_probe
        )
        reports.append(report)
        if not args.json:
            print(scrub("\n".join(report.lines())))
    if args.json:
        print(scrub(json.dumps([r.to_dict() for r in reports])))
    return 1 if any(r.failed for r in reports) else 0
