"""``emrd serve [--port N] [--host 127.0.0.1] [--registry FILE]``: the reference agents."""

from __future__ import annotations

import argparse
import sys
from pathlib import Path

from pytest_emrd.errors import ConfigError, check_range

HELP = "serve the built-in reference agents on an OpenAI-compatible endpoint"
DESCRIPTION = (
    "Run the scripted reference agents (scout, scout-decay-<m>, scout-window-<k>, "
    "scout-serial, prior) behind POST /v1/chat/completions and GET /v1/models, in the "
    "foreground until interrupted."
)


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--port", type=int, default=8765, help="port to bind (default 8765; 0 = any)")
    p.add_argument("--host", default="127.0.0.1", help="address to bind (default 127.0.0.1)")
    p.add_argument("--registry", type=Path, help="user model registry YAML")


def run(args: argparse.Namespace) -> int:
    from pytest_emrd.agent import load_registry
    from pytest_emrd.reference import ReferenceServer

    check_range("--port", args.port, 0, 65535)
    registry = load_registry(args.registry)
    try:
        server = ReferenceServer(host=args.host, port=args.port, registry=registry)
    except OSError as exc:
        raise ConfigError(
            f"--host={args.host} --port={args.port} cannot be bound ({exc}); "
            "choose a free port, or --port 0 for any."
        ) from exc
    print(f"emrd serve: reference agents at {server.base_url} (Ctrl-C to stop)", flush=True)
    try:
        server.serve_forever()
    except KeyboardInterrupt:
        print("emrd serve: stopped", file=sys.stderr)
    finally:
        server.close()
    return 0
