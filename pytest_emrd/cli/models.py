"""``emrd models [--models FILE] [--json]``: the model registry, and which keys are set.

One row per registered model: provider, default modality, model id, endpoint (scrubbed), the
API-key variable and whether it is set (:func:`key_state`; its value is never read out), and
the prices per million tokens. Parametric reference agents are listed once as patterns.
"""

from __future__ import annotations

import argparse
import json
import os
from pathlib import Path
from typing import Any

from pytest_emrd._scrub import scrub

PARAMETRIC = ("scout-decay-<mean steps>", "scout-window-<k>")


HELP = "list the model registry and whether each key is set"


def add_arguments(p: argparse.ArgumentParser) -> None:
    p.add_argument("--models", type=Path, help="user model registry YAML")
    p.add_argument("--json", action="store_true", help="print one JSON list of models")


def key_state(config: Any) -> str:
    """``set``, ``missing`` (required), ``unset`` (optional: no key is sent) or ``-`` (none)."""
    if config.api_key_env is None:
        return "-"
    if os.environ.get(config.api_key_env, "").strip():
        return "set"
    return "missing" if config.api_key_required else "unset"


def _price(value: float | None) -> str:
    return "-" if value is None else f"${value:g}"


def model_rows(registry: Any) -> list[dict[str, Any]]:
    """One plain dict per registered model (no secret: whether the key is set, the endpoint
    scrubbed)."""
    return [
        {
            "name": name,
            "provider": config.provider,
            "modality": config.modality,
            "model_id": config.model_id,
            "base_url": scrub(config.base_url) if config.base_url else "built-in reference server",
            "api_key_env": config.api_key_env,
            "key": key_state(config),
            "price_per_mtok_in": config.price_per_mtok_in,
            "price_per_mtok_out": config.price_per_mtok_out,
        }
        for name, config in sorted(registry.models.items())
    ]


def run(args: argparse.Namespace) -> int:
    from pytest_emrd.agent import load_registry
    from pytest_emrd.gate import render_table

    rows = model_rows(load_registry(args.models))
    if args.json:
        print(json.dumps(rows))
        return 0
    header = ["model", "provider", "modality", "key", "in $/M", "out $/M", "model id", "endpoint"]
    body = [
        [
            r["name"],
            r["provider"],
            r["modality"],
            f"{r['api_key_env']} {r['key']}" if r["api_key_env"] else "-",
            _price(r["price_per_mtok_in"]),
            _price(r["price_per_mtok_out"]),
            r["model_id"],
            r["base_url"],
        ]
        for r in rows
    ]
    print("\n".join(render_table(header, body)))
    print(f"parametric reference agents: {', '.join(PARAMETRIC)}")
    return 0
