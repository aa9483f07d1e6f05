"""``emrd thresholds RUN_DIR... [--out FILE]``: a starter thresholds.yaml from runs.

For each model and condition of the runs, a bound per gated metric at its bootstrap 95 % CI
end moved 0.05 further, commented with the value it came from: the runs pass it and a clear
regression fails (docs/user-guide/ci.md). Prints the file, or writes ``--out FILE`` (never
over an existing file). Exit status 0, or 2 on a usage error.
"""

from __future__ import annotations

import argparse
import shlex
import sys
from pathlib import Path

HELP = "write a starter thresholds.yaml from run directories"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("run_dirs", nargs="+", type=Path, metavar="RUN_DIR", help="run directories")
    p.add_argument("--out", type=Path, help="file to write (default: print it)")


def run(args: argparse.Namespace) -> int:
    from pytest_emrd._files import write_bytes_atomic
    from pytest_emrd.cli import check_run_dirs
    from pytest_emrd.errors import ConfigError
    from pytest_emrd.gate import starter_thresholds
    from pytest_emrd.metrics import GATE_METRICS
    from pytest_emrd.run import load_run_episodes, measure_episodes

    check_run_dirs(args.run_dirs)
    if args.out is not None and args.out.exists():
        raise ConfigError(
            f"--out {args.out} exists; the starter never overwrites gates: pass a new file "
            "name and merge by hand, or delete it first."
        )
    command = shlex.join(["emrd", "thresholds", *map(str, args.run_dirs)])
    metrics = measure_episodes(load_run_episodes(args.run_dirs))
    text = starter_thresholds(metrics, GATE_METRICS, command=command)
    if args.out is None:
        sys.stdout.write(text)
        return 0
    write_bytes_atomic(args.out, text.encode())
    check = shlex.join(["emrd", "gate", *map(str, args.run_dirs), "--thresholds", str(args.out)])
    print(f"{args.out}: gates for {len(metrics)} episodes; check them: {check}")
    return 0
