"""Model registry: which models exist, how to reach them and how they decode.

The registry ships as ``models.yaml`` next to this module (the paper's Table "Inference
Hyperparameters" for the seven VLMs, plus the built-in reference agents) and may be
extended or overridden by a user file: an entry whose name already exists updates the
shipped fields it names, a new name adds a model.

Reference agents with planted parameters resolve from their name, without a YAML entry
each: ``scout``, ``scout-decay-<mean steps>``, ``scout-window-<k>``, ``scout-serial``,
``prior``. A reference agent's ``model_id`` is its name (or the ``model_id`` of its entry)
with the behaviour version appended, ``scout@ref-2`` (see
:mod:`pytest_emrd.agent.reference._version`), so cassettes of older behaviour fail as drift.
"""

from __future__ import annotations

import os
import re
from dataclasses import dataclass, field, fields, replace
from importlib import resources
from pathlib import Path
from typing import Any, Final

import yaml

from pytest_emrd.agent.reference._version import versioned_id
from pytest_emrd.errors import ConfigError, check_choice, check_positive_int, check_range
from pytest_emrd.trajectory import MODALITIES

PROVIDERS: Final[tuple[str, ...]] = ("openai", "anthropic", "reference")

_ENV_REF = re.compile(r"\$\{(?P<var>[A-Z_][A-Z0-9_]*)(?::-(?P<default>[^}]*))?\}")
_DECAY = re.compile(r"^scout-decay-(?P<mean>\d+(?:\.\d+)?)$")
_WINDOW = re.compile(r"^scout-window-(?P<k>\d+)$")


@dataclass(frozen=True)
class ModelConfig:
    """One model as the episode loop and the clients see it."""

    name: str
    """Registry name (``gemini``, ``scout-decay-8``); also the cassette folder."""
    provider: str
    """``openai`` (any OpenAI-compatible endpoint), ``anthropic`` or ``reference``."""
    model_id: str
    """The ``model`` field sent to the endpoint (``<name>@<version>`` for reference agents)."""
    base_url: str | None = None
    """Endpoint root (``https://api.openai.com/v1``); None: the built-in reference server."""
    api_key_env: str | None = None
    """Environment variable holding the API key; None sends no key."""
    temperature: float = 0.0
    max_tokens: int = 4096
    single_image: bool = False
    """Send only the newest frame as an image; earlier frames travel as text."""
    modality: str = "vision"
    """Default modality of this model's episodes: ``vision``, ``text`` or ``both``."""
    timeout_s: float = 120.0
    """Per-request timeout in seconds."""
    max_retries: int = 4
    """Retries after the first attempt on 429, 5xx, transport errors and garbage bodies."""
    price_per_mtok_in: float | None = None
    """USD per million prompt tokens, for cost estimates; None if unknown."""
    price_per_mtok_out: float | None = None
    image_tokens: int = 255
    """Prompt tokens one 512x512 frame costs at this provider, for estimates before a probe
    measures it (255: one OpenAI high-detail tile)."""
    max_tokens_param: str = "max_tokens"
    """Body key carrying ``max_tokens`` (``max_completion_tokens`` for newer OpenAI models)."""
    planted: dict[str, Any] = field(default_factory=dict)
    """Planted cognition of a reference agent (``{"memory": "decay", "mean_steps": 8.0}``)."""

    def __post_init__(self) -> None:
        where = f"model {self.name!r}"
        check_choice(f"{where}: provider", self.provider, PROVIDERS)
        check_choice(f"{where}: modality", self.modality, MODALITIES)
        check_range(f"{where}: temperature", self.temperature, 0.0, 2.0)
        check_positive_int(f"{where}: max_tokens", self.max_tokens)
        check_positive_int(f"{where}: image_tokens", self.image_tokens)
        check_range(f"{where}: timeout_s", self.timeout_s, 0.001, 3600.0)
        if isinstance(self.max_retries, bool) or not isinstance(self.max_retries, int):
            raise ConfigError(f"{where}: max_retries={self.max_retries!r} must be a whole number.")
        check_range(f"{where}: max_retries", self.max_retries, 0, 20)
        if self.provider != "reference" and not self.base_url:
            raise ConfigError(f"{where}: base_url is required for provider={self.provider!r}.")
        if self.planted and self.provider != "reference":
            raise ConfigError(f"{where}: planted parameters are only for reference agents.")


_FIELDS: Final = {f.name for f in fields(ModelConfig)}


def _expand_env(value: str) -> str:
    """``${VAR}`` / ``${VAR:-default}`` in a registry string, resolved from the environment."""

    def sub(match: re.Match[str]) -> str:
        var, default = match.group("var"), match.group("default")
        found = os.environ.get(var)
        if found:
            return found
        if default is None:
            raise ConfigError(f"{value!r} needs the environment variable {var}; set it.")
        return default

    return _ENV_REF.sub(sub, value)


def _build(name: str, entry: Any, source: str) -> ModelConfig:
    if not isinstance(entry, dict):
        raise ConfigError(f"{source}: model {name!r} must be a mapping of fields.")
    unknown = sorted(set(entry) - _FIELDS)
    if unknown:
        raise ConfigError(
            f"{source}: model {name!r} has unknown field(s) {unknown}; "
            f"known fields: {', '.join(sorted(_FIELDS - {'name'}))}."
        )
    values = {k: _expand_env(v) if isinstance(v, str) else v for k, v in entry.items()}
    values["name"] = name
    if values.get("provider") == "reference":
        values["model_id"] = versioned_id(str(values.get("model_id") or name).partition("@")[0])
    try:
        return ModelConfig(**values)
    except TypeError as exc:
        raise ConfigError(f"{source}: model {name!r}: {exc}") from exc


def _read_yaml(text: str, source: str) -> dict[str, dict[str, Any]]:
    try:
        data = yaml.safe_load(text)
    except yaml.YAMLError as exc:
        raise ConfigError(f"{source} is not valid YAML: {exc}") from exc
    models = (data or {}).get("models") if isinstance(data, dict | None) else None
    if not isinstance(models, dict):
        raise ConfigError(f"{source} must hold a top-level 'models:' mapping of name -> fields.")
    return models


@dataclass(frozen=True)
class Registry:
    """Named model configurations; parametric reference names resolve on demand."""

    models: dict[str, ModelConfig]

    def names(self) -> tuple[str, ...]:
        """Registered names, sorted (parametric reference names are not enumerated)."""
        return tuple(sorted(self.models))

    def get(self, name: str) -> ModelConfig:
        """The configuration of ``name``; unknown names raise ConfigError listing the known."""
        if name in self.models:
            return self.models[name]
        planted = _parametric(name)
        if planted is not None and "scout" in self.models:
            base = self.models["scout"]
            return replace(
                base, name=name, model_id=versioned_id(name), planted={**base.planted, **planted}
            )
        raise ConfigError(
            f"model={name!r} is not in the registry. Known models: {', '.join(self.names())}; "
            "parametric reference agents: scout-decay-<mean steps>, scout-window-<k>. "
            "Add other models in a user registry file (models: {name: {...}})."
        )


def _parametric(name: str) -> dict[str, Any] | None:
    if match := _DECAY.match(name):
        mean = float(match["mean"])
        if mean < 1:
            raise ConfigError(
                f"model={name!r}: the mean retention must be >= 1 step (it is counted in "
                "whole steps out of view); use scout-decay-1 or more."
            )
        return {"memory": "decay", "mean_steps": mean}
    if match := _WINDOW.match(name):
        k = int(match["k"])
        check_positive_int(f"model={name!r}: window k", k)
        return {"memory": "window", "k": k}
    return None


def load_registry(user_file: Path | None = None) -> Registry:
    """The shipped registry, updated by ``user_file`` (entries merged field by field)."""
    shipped_text = resources.files("pytest_emrd.agent").joinpath("models.yaml").read_text()
    entries = _read_yaml(shipped_text, "pytest_emrd/agent/models.yaml")
    merged: dict[str, dict[str, Any]] = {k: dict(v) for k, v in entries.items()}
    source = "pytest_emrd/agent/models.yaml"
    if user_file is not None:
        source = str(user_file)
        try:
            user_text = Path(user_file).read_text()
        except OSError as exc:
            raise ConfigError(f"model registry file {user_file} cannot be read: {exc}") from exc
        for name, entry in _read_yaml(user_text, source).items():
            if not isinstance(entry, dict):
                raise ConfigError(f"{source}: model {name!r} must be a mapping of fields.")
            merged[str(name)] = {**merged.get(str(name), {}), **entry}
    return Registry({str(n): _build(str(n), e, source) for n, e in merged.items()})
