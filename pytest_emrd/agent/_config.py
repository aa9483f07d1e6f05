"""Model registry: which models exist, how to reach them and how they decode.

The registry ships as ``models.yaml`` next to this module and may be extended or overridden
by a user file, field by field (docs/reference/registry.md). Reference agents with planted
parameters resolve from their name, without a YAML entry each (``scout-decay-<mean steps>``,
``scout-window-<k>``, ``mimic-<knobs>``); a reference agent's ``model_id`` carries the
behaviour version (:mod:`pytest_emrd.agent._version`).
"""

from __future__ import annotations

import json
import os
import re
from collections.abc import Iterator
from dataclasses import dataclass, field, fields, replace
from importlib import resources
from pathlib import Path
from typing import Any, Final
from urllib.parse import urlsplit

import yaml

from pytest_emrd import _yaml
from pytest_emrd._files import check_slug
from pytest_emrd._scrub import scrub, watch_env, watch_value
from pytest_emrd.agent._knobs import FAMILY, check_knobs, mimic_knobs
from pytest_emrd.agent._version import versioned_id
from pytest_emrd.errors import ConfigError, check_choice, check_positive_int, check_range
from pytest_emrd.trajectory import MODALITIES

PROVIDERS: Final[tuple[str, ...]] = ("openai", "anthropic", "reference")

ANTHROPIC_VERSION: Final = "2026-10-21"
"""``anthropic-version`` sent to the Messages API; it answers HTTP 400 to ``temperature``,
``top_p`` and ``top_k``, even at their defaults (sources: the header of ``models.yaml``)."""
LEGACY_ANTHROPIC_VERSION: Final = "2023-06-01"
"""The previous version, which still accepts sampling parameters (``temperature`` in [0, 1])."""
SAMPLING_FIELDS: Final[tuple[str, ...]] = ("temperature", "top_p")
"""Registry fields that are sent only when set; ``null`` means "provider default"."""
REASONING_EFFORTS: Final = ("none", "minimal", "low", "medium", "high", "xhigh", "max")
"""``reasoning_effort`` and ``verbosity`` values of ``CreateChatCompletionRequest`` (OpenAI
OpenAPI spec, github:openai/openai-openapi commit f85dbe2, 2026-08-21)."""
VERBOSITIES: Final = ("low", "medium", "high")
MAX_TOKENS_PARAMS: Final[tuple[str, ...]] = ("max_tokens", "max_completion_tokens")
#: Body keys the client writes itself (the sampling ones from the registry fields of that name).
_CLIENT_KEYS: Final = {
    "model",
    "messages",
    "system",
    "stream",
    "top_k",
    *MAX_TOKENS_PARAMS,
    *SAMPLING_FIELDS,
}
_CREDENTIAL_HEADERS: Final = frozenset({"authorization", "x-api-key", "api-key", "x-goog-api-key"})
_CREDENTIAL_FIELD: Final = re.compile(
    r"api[_-]?key|secret|passw(?:or)?d|credential|private[_-]?key|access[_-]?key"
    r"|^(?:key|auth|authorization|sig|signature|token|bearer)$|[_-](?:token|auth)$",
    re.IGNORECASE,
)
"""``extra_body`` field names that look like credentials (``api_key``, ``access_token``,
``client_secret``): their value must be an environment variable reference, ``${VAR}``."""

_CREDENTIAL_HEADER: Final = re.compile(
    r"auth|token|key|cookie|secret|session|signature|password", re.IGNORECASE
)
"""``extra_headers`` names that look like credentials: their value must be a declared ``${VAR}``."""
_CONTROL: Final = re.compile(r"[\x00-\x1f\x7f]")
_ENV_NAME: Final = re.compile(r"[A-Z_][A-Z0-9_]*")
_ENV_REF = re.compile(r"\$\{(?P<var>[A-Z_][A-Z0-9_]*)(?::-(?P<default>[^}]*))?\}")
_DECAY = re.compile(r"^scout-decay-(?P<mean>\d+(?:\.\d+)?)$")
_WINDOW = re.compile(r"^scout-window-(?P<k>\d+)$")


@dataclass(frozen=True)
class ModelConfig:
    """One model as the episode loop and the clients see it. Every field, its default and
    meaning: docs/reference/registry.md (a test keeps that table complete)."""

    name: str
    provider: str
    model_id: str
    base_url: str | None = None
    api_key_env: str | None = None
    api_key_required: bool = True
    temperature: float | None = 0.0
    top_p: float | None = None
    max_tokens: int = 4096
    single_image: bool = False
    modality: str = "vision"
    timeout_s: float = 120.0
    max_retries: int = 4
    price_per_mtok_in: float | None = None
    price_per_mtok_out: float | None = None
    image_tokens: int = 255
    max_tokens_param: str = "max_tokens"
    extra_body: dict[str, Any] = field(default_factory=dict)
    extra_headers: dict[str, str] = field(default_factory=dict)
    planted: dict[str, Any] = field(default_factory=dict)
    env: tuple[str, ...] = ()

    def __post_init__(self) -> None:
        where = f"model {self.name!r}"
        texts = {f.name: getattr(self, f.name) for f in fields(self)}
        texts.update({f"extra_headers.{k}": v for k, v in self.extra_headers.items()})
        for name, text in texts.items():
            bad = _CONTROL.search(text) if isinstance(text, str) else None
            if bad is not None:  # the value may hold a secret: only the character is named
                raise ConfigError(
                    f"{where}: {name} holds the control character {bad.group()!r} at offset "
                    f"{bad.start()}; remove it (a line break or NUL in a URL, header or id "
                    "would split the request or garble the terminal)."
                )
        check_choice(f"{where}: provider", self.provider, PROVIDERS)
        check_choice(f"{where}: modality", self.modality, MODALITIES)
        _check_extras(self, where)
        _check_sampling(self, where)
        check_positive_int(f"{where}: max_tokens", self.max_tokens)
        check_positive_int(f"{where}: image_tokens", self.image_tokens)
        check_choice(f"{where}: max_tokens_param", self.max_tokens_param, MAX_TOKENS_PARAMS)
        if not isinstance(self.api_key_required, bool):
            raise ConfigError(
                f"{where}: api_key_required={self.api_key_required!r} must be true or false."
            )
        check_range(f"{where}: timeout_s", self.timeout_s, 0.001, 3600.0)
        if isinstance(self.max_retries, bool) or not isinstance(self.max_retries, int):
            raise ConfigError(f"{where}: max_retries={self.max_retries!r} must be a whole number.")
        check_range(f"{where}: max_retries", self.max_retries, 0, 20)
        if self.provider != "reference" and not self.base_url:
            raise ConfigError(f"{where}: base_url is required for provider={self.provider!r}.")
        if self.base_url:
            _check_base_url(self, where)
        if self.planted and self.provider != "reference":
            raise ConfigError(f"{where}: planted parameters are only for reference agents.")
        check_knobs(where, self.planted)


def _check_number(name: str, value: Any, low: float, high: float) -> None:
    if value is None:
        return
    if isinstance(value, bool) or not isinstance(value, int | float):
        raise ConfigError(f"{name}={value!r} must be a number in [{low}, {high}] or null.")
    check_range(name, value, low, high)


def _check_sampling(config: ModelConfig, where: str) -> None:
    anthropic_version = {k.lower(): v for k, v in config.extra_headers.items()}.get(
        "anthropic-version", ANTHROPIC_VERSION
    )
    if config.provider == "anthropic" and anthropic_version != LEGACY_ANTHROPIC_VERSION:
        sent = [k for k in SAMPLING_FIELDS if getattr(config, k) is not None]
        if sent:
            raise ConfigError(
                f"{where}: {sent[0]}={getattr(config, sent[0])!r} is rejected by the Anthropic "
                f"Messages API version {anthropic_version}; allowed: null (provider default), "
                f"or pin extra_headers: {{anthropic-version: '{LEGACY_ANTHROPIC_VERSION}'}}."
            )
    high = 1.0 if config.provider == "anthropic" else 2.0
    _check_number(f"{where}: temperature", config.temperature, 0.0, high)
    _check_number(f"{where}: top_p", config.top_p, 0.0, 1.0)


def _check_base_url(config: ModelConfig, where: str) -> None:
    """An http(s) URL without userinfo: httpx would send ``user:password`` as Basic auth in
    place of the key, and the password would sit in the registry file."""
    try:
        parts = urlsplit(config.base_url or "")
        parts.port  # noqa: B018 - raises ValueError on a port that is not a number
    except ValueError as exc:
        raise ConfigError(
            f"{where}: base_url is not a URL ({exc}); write e.g. https://api.example.com/v1."
        ) from None
    if parts.scheme not in ("http", "https") or not parts.hostname:
        raise ConfigError(
            f"{where}: base_url={scrub(config.base_url or '')!r} must be an http:// or https:// "
            "URL with a host, e.g. https://api.example.com/v1."
        )
    if "@" in parts.netloc:
        anthropic = config.provider == "anthropic"
        header = "x-api-key header" if anthropic else "Authorization header, as a Bearer token"
        raise ConfigError(
            f"{where}: base_url carries a user name or password before '@' "
            f"({scrub(config.base_url or '')}); remove it: the key goes in the environment "
            f"variable named by api_key_env, which is sent in the {header}."
        )


def _credential_fields(body: Any, path: str = "extra_body") -> Iterator[tuple[str, Any]]:
    """``(dotted path, value)`` of every field of ``body`` whose name looks like a credential."""
    if isinstance(body, list):
        body = dict(enumerate(body))
    for key, value in body.items() if isinstance(body, dict) else ():
        at = f"{path}.{key}" if isinstance(key, str) else f"{path}[{key}]"
        if isinstance(key, str) and _CREDENTIAL_FIELD.search(key):
            yield at, value
        yield from _credential_fields(value, at)


def _check_extras(config: ModelConfig, where: str) -> None:
    for name, value in (("extra_body", config.extra_body), ("extra_headers", config.extra_headers)):
        if not isinstance(value, dict) or not all(isinstance(k, str) for k in value):
            raise ConfigError(
                f"{where}: {name} must be a mapping of name -> value, got {type(value).__name__}."
            )
    owned = sorted(set(config.extra_body) & _CLIENT_KEYS)
    if owned:
        raise ConfigError(
            f"{where}: extra_body may not set {owned[0]!r}: the client writes it "
            f"(use the registry field of that name where there is one; allowed extra_body "
            f"keys are any others, e.g. reasoning_effort)."
        )
    checked = {"reasoning_effort": REASONING_EFFORTS, "verbosity": VERBOSITIES}
    for key, allowed in checked.items() if config.provider == "openai" else ():
        if key in config.extra_body:
            check_choice(f"{where}: extra_body.{key}", config.extra_body[key], allowed)
    try:
        json.dumps(config.extra_body, allow_nan=False)
    except (TypeError, ValueError) as exc:
        raise ConfigError(
            f"{where}: extra_body is not JSON ({exc}); write numbers, text, true/false, null, "
            "lists and mappings only (quote a date: '2026-01-01')."
        ) from None
    for header, value in config.extra_headers.items():
        if header.lower() in _CREDENTIAL_HEADERS:
            raise ConfigError(
                f"{where}: extra_headers may not carry the credential header {header}; keys "
                "come only from the environment variable named by api_key_env."
            )
        if not isinstance(value, str):
            raise ConfigError(
                f"{where}: extra_headers.{header} must be a string, got "
                f"{type(value).__name__}; quote the value in the registry file."
            )


_FIELDS: Final = {f.name for f in fields(ModelConfig)}


def _expand_env(value: Any, where: str, field_name: str, declared: frozenset[str]) -> Any:
    """``${VAR}`` / ``${VAR:-default}`` in a registry string (or in those of a mapping or list),
    resolved from the environment; only ``declared`` variables (``api_key_env`` and ``env``),
    each then a secret (:func:`~pytest_emrd._scrub.watch_env`)."""
    if isinstance(value, dict):
        return {k: _expand_env(v, where, f"{field_name}.{k}", declared) for k, v in value.items()}
    if isinstance(value, list):
        return [_expand_env(v, where, field_name, declared) for v in value]
    if not isinstance(value, str):
        return value

    def sub(match: re.Match[str]) -> str:
        var, default = match.group("var"), match.group("default")
        if var not in declared:
            raise ConfigError(
                f"{where}: {field_name} uses ${{{var}}}, which the model does not declare; add "
                f"env: [{var}] to the model (an entry reads only the variables it declares, "
                "and their values are then removed from every file and log)."
            )
        watch_env([var])
        found = os.environ.get(var)
        if found:
            return found
        if default is None:
            raise ConfigError(
                f"{where}: {field_name} needs the environment variable {var}, which is not "
                f"set; export {var}=..., or write ${{{var}:-default}} for a fallback."
            )
        watch_value(default)
        return default

    return _ENV_REF.sub(sub, value)


def _written_out(value: Any) -> bool:
    """Whether a credential-like value is written out, not a bare ``${VAR}`` reference (a
    ``${VAR:-default}`` writes its default out)."""
    ref = _ENV_REF.fullmatch(value) if isinstance(value, str) else None
    return ref is None or ref.group("default") is not None


def _check_header_credentials(entry: dict[str, Any], where: str) -> None:
    """Credential-like ``extra_headers`` take only a ``${VAR}`` reference, never a value."""
    headers = entry.get("extra_headers")
    for header, value in headers.items() if isinstance(headers, dict) else ():
        if (
            not isinstance(header, str)
            or header.lower() in _CREDENTIAL_HEADERS
            or not _CREDENTIAL_HEADER.search(header)
        ):
            continue  # (the four key headers are refused with or without a reference)
        if _written_out(value):
            raise ConfigError(
                f"{where}: extra_headers.{header} looks like a credential and is written out; "
                "write it as a reference to a declared variable, ${MY_SECRET} with "
                "env: [MY_SECRET], and export MY_SECRET (its value is then removed from every "
                "file and log)."
            )


def _check_body_credentials(entry: dict[str, Any], where: str) -> None:
    """Credential-like ``extra_body`` fields must be ``${VAR}`` references (then watched)."""
    for at, value in _credential_fields(entry.get("extra_body") or {}):
        if _written_out(value):
            raise ConfigError(
                f"{where}: {at} looks like a credential and is written out; a request body "
                "is stored in every cassette, so write the value as an environment variable "
                "reference, ${MY_SECRET}, and export MY_SECRET (its value is then removed "
                "from every file and log)."
            )


Lines = dict[tuple[str, str | None], int]
"""``(model, field)`` -> 1-based line of that key in a registry file (``field`` None: the
model's own key)."""
#: The field a ModelConfig error names: ``model 'x': <field>...``.
_FIELD_IN_ERROR: Final = re.compile(r"^model '[^']*': ([a-z_]+)")


def _at(source: str, lines: Lines, name: str, field_name: str | None = None) -> str:
    line = lines.get((name, field_name)) or lines.get((name, None))
    return f"{source}, line {line}" if line else source


def _build(name: str, entry: dict[str, Any], source: str, lines: Lines) -> ModelConfig:
    at = _at(source, lines, name)
    becomes = "a model name is a cassette folder and part of every episode file name"
    check_slug(at, name, becomes=becomes)
    unknown = sorted(set(entry) - _FIELDS)
    if unknown:
        raise ConfigError(
            f"{_at(source, lines, name, unknown[0])}: model {name!r} has unknown field(s) "
            f"{unknown}; known fields: {', '.join(sorted(_FIELDS - {'name'}))}."
        )
    _check_body_credentials(entry, f"{_at(source, lines, name, 'extra_body')}: model {name!r}")
    _check_header_credentials(entry, f"{_at(source, lines, name, 'extra_headers')}: model {name!r}")
    env = entry.get("env") or []
    if not isinstance(env, list) or not all(
        isinstance(v, str) and _ENV_NAME.fullmatch(v) for v in env
    ):
        raise ConfigError(
            f"{_at(source, lines, name, 'env')}: model {name!r}: env={env!r} must be a list of "
            "environment variable names (env: [MY_BASE_URL, MY_TOKEN])."
        )
    declared = frozenset((*env, entry.get("api_key_env") or ""))
    watch_env(declared)
    values = {
        k: _expand_env(v, f"{_at(source, lines, name, k)}: model {name!r}", k, declared)
        for k, v in entry.items()
    }
    values["env"] = tuple(env)
    values["name"] = name
    if values.get("provider") == "anthropic":
        values.setdefault("temperature", None)  # Appendix C: Claude at the provider default
    if values.get("provider") == "reference":
        values["model_id"] = versioned_id(str(values.get("model_id") or name).partition("@")[0])
    try:
        return ModelConfig(**values)
    except TypeError as exc:
        raise ConfigError(f"{at}: model {name!r}: {exc}") from None
    except ConfigError as exc:
        named = _FIELD_IN_ERROR.match(str(exc))
        where = _at(source, lines, name, named.group(1) if named else None)
        raise ConfigError(f"{where}: {exc}") from None


def _read_yaml(text: str, source: str) -> tuple[dict[str, dict[str, Any]], Lines]:
    """The ``models:`` mapping of a registry file, and where each model and field is written."""
    root = _yaml.compose(text, source)
    data = _yaml.scalar(root) if root is not None else None
    models = data.get("models") if isinstance(data, dict) else None
    if root is None or not isinstance(models, dict):
        raise ConfigError(f"{source} must hold a top-level 'models:' mapping of name -> fields.")
    lines: Lines = {}
    # ``models`` is a mapping, so its one key node (duplicates are refused) holds a mapping node
    for key, value in root.value:
        if key.value != "models":
            continue
        for model_key, model in value.value:
            lines[(str(model_key.value), None)] = model_key.start_mark.line + 1
            for field_key, _ in model.value if isinstance(model, yaml.MappingNode) else ():
                lines[(str(model_key.value), str(field_key.value))] = field_key.start_mark.line + 1
    return models, lines


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
        base_name, planted = _parametric(name) or (None, {})
        if base_name in self.models:
            base = self.models[base_name]
            return replace(
                base, name=name, model_id=versioned_id(name), planted={**base.planted, **planted}
            )
        raise ConfigError(
            f"model={name!r} is not in the registry. Known models: {', '.join(self.names())}; "
            "parametric reference agents: scout-decay-<mean steps>, scout-window-<k>, "
            "mimic-<knobs> (s<sigma>, p<dup>, h<halluc>, q<fail>, r<repair>, a<invalid>, b<back>, "
            "spawn; e.g. mimic-s0.3-p0.5). "
            "Add other models in a user registry file (models: {name: {...}}) and pass it "
            "with --emrd-models FILE (ini: emrd_models = FILE; emrd gate --models FILE)."
        )


def _parametric(name: str) -> tuple[str, dict[str, Any]] | None:
    """(base entry, planted overrides) of a parametric reference name, or None."""
    knobs = mimic_knobs(name)
    if knobs is not None:
        return FAMILY, knobs
    if match := _DECAY.match(name):
        mean = float(match["mean"])
        if mean < 1:
            raise ConfigError(
                f"model={name!r}: the mean retention must be >= 1 step (it is counted in "
                "whole steps out of view); use scout-decay-1 or more."
            )
        return "scout", {"memory": "decay", "mean_steps": mean}
    if match := _WINDOW.match(name):
        k = int(match["k"])
        check_positive_int(f"model={name!r}: window k", k)
        return "scout", {"memory": "window", "k": k}
    return None


def load_registry(user_file: Path | None = None) -> Registry:
    """The shipped registry, updated by ``user_file`` (entries merged field by field).

    :param user_file: A ``models.yaml``; None for the shipped registry alone.
    :returns: The merged :class:`Registry`.
    """
    source = "pytest_emrd/agent/models.yaml"
    shipped_text = resources.files("pytest_emrd.agent").joinpath("models.yaml").read_text()
    entries, lines = _read_yaml(shipped_text, source)
    merged = dict(entries)  # entries are replaced, never changed in place
    if user_file is not None:
        source = str(user_file)
        user_text = _yaml.read_text(
            Path(user_file), what="model registry file", flag="--emrd-models (emrd gate --models)"
        )
        user, lines = _read_yaml(user_text, source)
        for name, entry in user.items():
            if not isinstance(entry, dict):
                raise ConfigError(
                    f"{_at(source, lines, str(name))}: model {name!r} must be a mapping of fields."
                )
            merged[str(name)] = {**merged.get(str(name), {}), **entry}
    return Registry({n: _build(n, e, source, lines) for n, e in merged.items()})
