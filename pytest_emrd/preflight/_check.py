"""Preflight of one model, checks in order: ``key`` (the registry's API-key variable is set;
its value is never shown), ``url`` (``GET /models`` answers and, when it lists models, lists
ours), ``probe`` (one real request of the episode loop, a full window of real frames, is
answered in our JSON protocol), ``images`` (the endpoint took that many frames), ``context``
(the context length the server reports holds the largest request plus ``max_tokens``) and
``estimate`` (tokens and cost of the live episodes). A refusal vLLM explains fails
``images`` or ``context`` with the ``vllm serve`` flag that fixes it.
"""

from __future__ import annotations

import os
import shlex
import time
from dataclasses import dataclass
from typing import Any, Final

import httpx

from pytest_emrd._serde import JsonRecord
from pytest_emrd.agent import (
    HISTORY_TURNS,
    ChatClient,
    ModelConfig,
    build_request,
    load_registry,
    make_client,
    parse_reply,
)
from pytest_emrd.errors import EmrdError
from pytest_emrd.preflight._estimate import (
    CostEstimate,
    Measured,
    count_images,
    estimate_cost,
    request_tokens,
    sample_reply,
    sweep,
)
from pytest_emrd.preflight._server import context_fix, models_url, server_info, vllm_refusal
from pytest_emrd.trajectory import EpisodeSpec

_EXCERPT: Final = 160


@dataclass(frozen=True)
class Check:
    """One preflight check and what it found."""

    name: str
    status: str
    """``pass``, ``fail``, ``skip`` (a prerequisite failed), ``warn`` (go ahead, read it) or
    ``info``."""
    detail: str
    fix: str = ""
    """What to do when it failed."""


@dataclass(frozen=True)
class PreflightReport(JsonRecord):
    """Every check of one model, and the cost estimate of its live episodes."""

    model: str
    checks: tuple[Check, ...]
    estimate: CostEstimate | None = None
    models_file: str | None = None
    """The user registry the run was given (``--emrd-models``): the check-again command
    needs it to know the model."""

    @property
    def failed(self) -> Check | None:
        """The first failing check, or ``None``."""
        return next((c for c in self.checks if c.status == "fail"), None)

    def lines(self) -> list[str]:
        """The report as terminal lines: one per check, the fix under a failure."""
        width = max(len(c.name) for c in self.checks)
        out = [f"emrd preflight {self.model}:"]
        for c in self.checks:
            out.append(f"  {c.status.upper():<4}  {c.name:<{width}}  {c.detail}")
            if c.status == "fail" and c.fix:
                out.append(f"        {'':<{width}}  fix: {c.fix}")
        return out

    def message(self) -> str:
        """One sentence for a blocked run: the model, the failing check and the fix."""
        failed = self.failed
        if failed is None:
            return f"preflight of model {self.model!r} passed."
        return (
            f"preflight of model {self.model!r} failed at '{failed.name}': "
            f"{failed.detail.rstrip('.')}. Fix: {failed.fix.rstrip('.')}. "
            f"Check again with: {self.check_command}"
        )

    @property
    def check_command(self) -> str:
        """``emrd check`` for this model, with the registry that defines it."""
        registry = f" --emrd-models={shlex.quote(self.models_file)}" if self.models_file else ""
        return f"emrd check --emrd-model={shlex.quote(self.model)}{registry}"


def _key(config: ModelConfig) -> Check:
    if config.api_key_env is None:
        return Check("key", "pass", "no API key needed")
    if _key_value(config):
        return Check("key", "pass", f"{config.api_key_env} is set")
    if not config.api_key_required:
        return Check("key", "pass", f"{config.api_key_env} is not set: no key is sent")
    return Check(
        "key",
        "fail",
        f"{config.api_key_env} is not set",
        f"export {config.api_key_env}=<your key> (or replay the committed cassettes with "
        "--emrd-record-mode=none)",
    )


def _excerpt(text: str) -> str:
    text = " ".join(text.split())
    return text[:_EXCERPT] + ("..." if len(text) > _EXCERPT else "")


def _key_value(config: ModelConfig) -> str:
    return os.environ.get(config.api_key_env or "", "").strip()


@dataclass
class _Probe:
    """Inputs and outcome of the probe call."""

    config: ModelConfig
    messages: list[dict[str, Any]]
    images: int
    estimated: int
    measured: Measured | None = None


def _send(probe: _Probe, client: ChatClient) -> list[Check]:
    start = time.perf_counter()
    try:
        response = client.complete(probe.messages)
    except EmrdError as exc:
        return _refused(probe, str(exc))
    finally:
        client.close()
    seconds = time.perf_counter() - start
    usage = response.usage
    probe.measured = Measured(
        prompt_tokens=usage.prompt_tokens or probe.estimated,
        estimated_prompt_tokens=probe.estimated,
        completion_tokens=usage.completion_tokens,
        reply=response.text,
        seconds=seconds,
    )
    reply = parse_reply(response.text)
    if reply.error is not None:
        probe_check = Check(
            "probe",
            "fail",
            f"the reply is not in the EMRD JSON protocol ({reply.error}): "
            f"{_excerpt(response.text)!r}",
            "check the model and its chat template follow the system prompt's REPLY FORMAT "
            "(one JSON object with cognitive_map and action)",
        )
    else:
        probe_check = Check(
            "probe",
            "pass",
            f"answered in {seconds:.1f} s: action {reply.action}, {len(reply.cognitive_map)} map "
            f"entries, {usage.prompt_tokens:,} prompt + {usage.completion_tokens:,} completion "
            "tokens",
        )
    if probe.images == 0:
        return [probe_check, Check("images", "info", "text modality: no frames are sent")]
    return [probe_check, Check("images", "pass", f"took {probe.images} frames in one request")]


def _refused(probe: _Probe, message: str) -> list[Check]:
    config, said = probe.config, _excerpt(message)
    refusal = vllm_refusal(
        message, images=probe.images, max_tokens=config.max_tokens, prompt_tokens=probe.estimated
    )
    if refusal is not None:
        return [
            Check("probe", "fail", f"the server refused the request: {refusal.said}", refusal.fix),
            Check(refusal.check, "fail", refusal.said, refusal.fix),
        ]
    if "HTTP 401" in message or "HTTP 403" in message:
        fix = (
            f"check the key in {config.api_key_env}"
            if config.api_key_env
            else "the server wants a key (vLLM started with --api-key?): set api_key_env for "
            f"{config.name!r} in a user registry (--emrd-models FILE)"
        )
        return [Check("probe", "fail", f"credentials rejected: {said}", fix)]
    if "HTTP 404" in message:
        fix = f"check base_url and model_id={config.model_id!r} (a user registry overrides them)"
        return [Check("probe", "fail", f"not found: {said}", fix)]
    return [Check("probe", "fail", said, "see the server's message above")]


def _context(probe: _Probe, max_model_len: int | None) -> Check:
    if max_model_len is None:
        return Check("context", "info", "context length not reported by the server")
    prompt = probe.measured.prompt_tokens if probe.measured else probe.estimated
    max_tokens = probe.config.max_tokens
    detail = (
        f"server context {max_model_len:,} tokens; a full window needs ~{prompt:,} + "
        f"max_tokens {max_tokens:,}"
    )
    if prompt + max_tokens <= max_model_len:
        return Check("context", "pass", detail)
    return Check("context", "fail", detail, context_fix(prompt, max_tokens, max_model_len))


def _listing_headers(config: ModelConfig) -> dict[str, str]:
    """What the probe will send besides the body: the provider's headers and the key."""
    headers = dict(build_request(config, [{"role": "user", "content": "."}]).headers)
    if key := _key_value(config):
        if config.provider == "anthropic":
            headers["x-api-key"] = key
        else:
            headers["Authorization"] = f"Bearer {key}"
    return headers


def _url(config: ModelConfig, base_url: str) -> tuple[Check, int | None]:
    url = models_url(config.provider, base_url)
    info = server_info(url, config.model_id, headers=_listing_headers(config))
    if info.refused:
        sent = bool(_key_value(config))
        detail = f"{info.url} answered HTTP {info.status}: " + (
            f"the key in {config.api_key_env} was refused"
            if sent
            else "the endpoint wants a key and none was sent"
        )
        fix = (
            f"check the key in {config.api_key_env}"
            if sent
            else f"set api_key_env for {config.name!r} in your registry (--emrd-models FILE) "
            "and export that variable"
            if config.api_key_env is None
            else f"export {config.api_key_env}=<your key>"
        )
        return Check("url", "fail", detail, fix), None
    if not info.reachable:
        local = httpx.URL(base_url).host in ("localhost", "127.0.0.1", "::1")
        fix = "check this machine's network access to it, or the model's base_url"
        if local and config.name in load_registry(None).names():
            fix = (
                "start the server (the `vllm serve` command of each model: docs/user-guide/"
                "vllm.md in the pytest-emrd repository) or point the model's base_url at it "
                "(its EMRD_*_BASE_URL variable, or a user registry)"
            )
        elif local:  # a model of the user's own registry
            fix = (
                f"start the server that serves model_id={config.model_id!r} there, or set "
                f"base_url of {config.name!r} in your registry (--emrd-models FILE) to its "
                "address"
            )
        return Check("url", "fail", f"cannot reach {base_url} ({info.error})", fix), None
    if info.serves(config.model_id) is False:
        detail = f"{base_url} serves {', '.join(info.served[:5])}, not {config.model_id}"
        fix = (
            f"start vLLM with --served-model-name {config.model_id}, or set model_id in a "
            "user registry"
        )
        return Check("url", "fail", detail, fix), None
    return Check("url", "pass", f"{info.url} answered HTTP {info.status}"), info.max_model_len


def preflight(
    config: ModelConfig,
    spec: EpisodeSpec,
    *,
    episodes: int,
    probe: bool = True,
    models_file: str | None = None,
) -> PreflightReport:
    """Check that ``config`` can run ``episodes`` live episodes like ``spec`` (its modality,
    variant and budget); ``probe=False`` checks the key and estimates without any network.
    ``models_file``: the user registry that defines it, for the check-again command.

    :param config: The model's registry entry.
    :param spec: An episode like those to run.
    :param episodes: How many live episodes.
    :param probe: Ask the endpoint (one listing, one sample request).
    :param models_file: The user registry file, if any.
    :returns: The :class:`PreflightReport`: checks, estimates and refusals.
    """
    window = sweep(spec, single_image=config.single_image)
    messages = window.request(HISTORY_TURNS, sample_reply())
    tokens = request_tokens(messages, image_tokens=config.image_tokens)
    state = _Probe(config, messages, count_images(messages), tokens)
    checks = [_key(config)]
    if probe:
        from pytest_emrd.reference import base_url_of  # a reference agent: the built-in server

        base_url = base_url_of(config)
        url, max_model_len = _url(config, base_url)
        checks.append(url)
        if checks[0].status == "fail" or url.status == "fail":
            checks.append(Check("probe", "skip", "needs the key and a reachable endpoint"))
        else:
            checks += _send(state, make_client(config, base_url=base_url))
            if all(c.name != "context" for c in checks):
                checks.append(_context(state, max_model_len))
    estimate = estimate_cost(
        config, window, episodes=episodes, max_steps=spec.max_steps, measured=state.measured
    )
    if estimate.warning is not None:
        checks.append(Check("usage", "warn", estimate.warning))
    checks.append(Check("estimate", "info", estimate.line()))
    return PreflightReport(config.name, tuple(checks), estimate, models_file)
