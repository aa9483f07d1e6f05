"""Model clients on httpx (which vcrpy patches): OpenAI-compatible and Anthropic Messages.

Request bodies depend only on the configuration and the messages (:func:`build_request`, which
the conformance tests validate against each provider's published request schema): no
timestamps, request ids or secrets (keys travel in headers, which cassettes strip).
``timeout_s`` is a deadline on each attempt, connect to last byte: :class:`DeadlineTransport`
shuts the connection down when it passes, so a server dripping its reply cannot hold a
request open. Not the official SDKs: their retry loop obeys ``Retry-After`` without a cap and
logs nothing on our logger, and they would bring a second request path and pydantic for
bodies that are plain JSON.
"""

from __future__ import annotations

import contextlib
import os
import socket
import threading
import time
from collections.abc import Callable
from dataclasses import dataclass
from typing import Any, Final, Protocol

import httpx

from pytest_emrd import frames
from pytest_emrd._wire import encode_body
from pytest_emrd.agent._config import ANTHROPIC_VERSION, SAMPLING_FIELDS, ModelConfig
from pytest_emrd.agent._history import JPEG_DATA_URL
from pytest_emrd.agent._retry import RetryPolicy, post_json
from pytest_emrd.errors import ConfigError
from pytest_emrd.trajectory import Usage


@dataclass(frozen=True)
class ProviderRequest:
    """One request as it goes on the wire, less the API key (added by the client)."""

    path: str
    headers: dict[str, str]
    body: dict[str, Any]


@dataclass(frozen=True)
class ChatResponse:
    """The text of a completion and the tokens the provider billed."""

    text: str
    usage: Usage


class ChatClient(Protocol):
    """Sends one chat request (OpenAI-format messages) and returns the reply."""

    def complete(self, messages: list[dict[str, Any]]) -> ChatResponse: ...

    def close(self) -> None: ...


def endpoint_url(base_url: str, path: str) -> str:
    """``base_url`` with ``path`` appended to its path, query and fragment kept
    (``https://x.azure.com/v1?api-version=1`` -> ``.../v1/chat/completions?api-version=1``).

    :param base_url: The endpoint, perhaps with a query.
    :param path: The path to append (``/chat/completions``).
    :returns: The joined URL.
    """
    base = httpx.URL(base_url)
    return str(base.copy_with(path=base.path.rstrip("/") + path))


class _Deadline:
    """One attempt's deadline: when it passes, the attempt's connection is shut down (a read
    blocked on it returns at once). The timer starts with the first connection, so a replay,
    which never connects, starts no thread."""

    _STREAM_EVENTS = ("connection.connect_tcp.complete", "connection.start_tls.complete")

    def __init__(self, seconds: float) -> None:
        self.end = time.monotonic() + seconds
        self.expired = False
        self._lock = threading.Lock()
        self._sock: socket.socket | None = None
        self._timer: threading.Timer | None = None

    def trace(self, event: str, info: dict[str, Any]) -> None:
        """httpcore's ``trace`` extension: keep the newest socket of the attempt."""
        if event not in self._STREAM_EVENTS or info.get("return_value") is None:
            return
        sock = info["return_value"].get_extra_info("socket")
        with self._lock:
            self._sock = sock
            if self._timer is None and not self.expired:
                self._timer = threading.Timer(max(0.0, self.end - time.monotonic()), self.expire)
                self._timer.daemon = True
                self._timer.start()
        if self.expired or time.monotonic() >= self.end:
            self.expire()

    def expire(self) -> None:
        with self._lock:
            self.expired, sock = True, self._sock
        if sock is not None:
            with contextlib.suppress(OSError):  # already closed: the attempt ended on its own
                sock.shutdown(socket.SHUT_RDWR)

    def cancel(self) -> None:
        with self._lock:
            if self._timer is not None:
                self._timer.cancel()


class DeadlineTransport(httpx.BaseTransport):
    """A transport that gives each request at most ``seconds``, connect to last byte (the
    whole body is read inside the deadline), raising :class:`httpx.ReadTimeout` past it."""

    def __init__(self, inner: httpx.BaseTransport, seconds: float) -> None:
        self.inner = inner
        self.seconds = seconds

    def handle_request(self, request: httpx.Request) -> httpx.Response:
        deadline = _Deadline(self.seconds)
        given = request.extensions
        request.extensions = {**given, "trace": deadline.trace}
        try:
            response = self.inner.handle_request(request)
            try:
                raw = b"".join(response.iter_raw())
            finally:
                response.close()
        except httpx.TransportError:
            if not deadline.expired:
                raise
        finally:
            request.extensions = given
            deadline.cancel()
        if deadline.expired:
            raise httpx.ReadTimeout(
                f"no complete reply within timeout_s={self.seconds:g} s", request=request
            )
        return httpx.Response(
            response.status_code,
            headers=response.headers,
            stream=httpx.ByteStream(raw),
            extensions={k: v for k, v in response.extensions.items() if k != "network_stream"},
        )

    def close(self) -> None:
        self.inner.close()


class _NoCookies(httpx.Cookies):
    """Cookies that keep nothing: requests are built without the client's cookies (see
    :mod:`._retry`), so reading each reply's ``Set-Cookie`` headers would be wasted."""

    def extract_cookies(self, response: httpx.Response) -> None:
        """Keep no cookie of ``response``."""


class _HttpClient:
    """One httpx client, a retry policy and the API key; a subclass gives ``_key_header`` (the
    key's header and the prefix of its value) and ``_read`` (reply text and usage from the
    decoded response).

    Without a ``transport``, httpx's transports (proxies included) go under
    :class:`DeadlineTransport`, without keep-alive so that each attempt's connection is its
    own and can be shut at its deadline; with ``deadline=False`` (a replay, which the cassette
    answers before any connection) they are httpx's own. ``encode`` makes a body the bytes
    sent: its wire JSON, or in a replay its canonical form."""

    _key_header: tuple[str, str]
    _read: Callable[[Any], ChatResponse]

    def __init__(
        self,
        config: ModelConfig,
        *,
        base_url: str,
        policy: RetryPolicy | None = None,
        transport: httpx.BaseTransport | None = None,
        require_key: bool = True,
        deadline: bool = True,
        encode: Callable[[Any], bytes] = encode_body,
    ) -> None:
        self.config, self._encode = config, encode
        self.base_url = base_url
        self.policy = policy or RetryPolicy(max_retries=config.max_retries)
        key = os.environ.get(config.api_key_env, "").strip() if config.api_key_env else ""
        if not key and config.api_key_env and require_key and config.api_key_required:
            raise ConfigError(
                f"model {config.name!r} needs an API key in the environment variable "
                f"{config.api_key_env}; set it, or replay the recorded cassettes "
                "(record mode none)."
            )
        self._key = key or None
        timeout = httpx.Timeout(config.timeout_s)
        if transport is not None or not deadline:
            self._http = httpx.Client(timeout=timeout, transport=transport)
        else:
            self._http = httpx.Client(
                timeout=timeout, limits=httpx.Limits(max_keepalive_connections=0)
            )
            self._http._transport = DeadlineTransport(self._http._transport, config.timeout_s)
            self._http._mounts = {
                pattern: None if mounted is None else DeadlineTransport(mounted, config.timeout_s)
                for pattern, mounted in self._http._mounts.items()
            }
        self._http._cookies = _NoCookies()  # httpx has no public switch for its cookie jar
        self._urls: dict[str, tuple[httpx.URL, str]] = {}

    def complete(self, messages: list[dict[str, Any]]) -> ChatResponse:
        """Send :func:`build_request` for ``messages`` (plus the key) and read the reply."""
        request = build_request(self.config, messages)
        name, prefix = self._key_header
        headers = request.headers | {name: prefix + self._key} if self._key else request.headers
        if request.path not in self._urls:  # parsed once; logged without userinfo or query
            url = httpx.URL(endpoint_url(self.base_url, request.path))
            shown = str(url.copy_with(userinfo=b"", query=None, fragment=None))
            self._urls[request.path] = url, shown
        return post_json(
            self._http,
            *self._urls[request.path],
            content=self._encode(request.body),
            headers=headers,
            policy=self.policy,
            read=self._read,
            key=self._key,
        )

    def close(self) -> None:
        self._http.close()

    def __enter__(self) -> _HttpClient:
        return self

    def __exit__(self, *exc: object) -> None:
        self.close()


class OpenAICompatibleClient(_HttpClient):
    """``POST {base_url}/chat/completions``: vLLM, OpenAI, Gemini, the reference server.

    :param config: The model's registry entry.
    :param base_url: The endpoint, without ``/chat/completions``.
    :param policy: Retries and timeouts; None for ``config.max_retries`` with the defaults.
    :param transport: An httpx transport to use instead of the network (tests).
    :param require_key: Raise :class:`ConfigError` when the key's variable is unset.
    :param deadline: Give each attempt ``timeout_s`` (without a ``transport``).
    :param encode: The bytes sent for a body (a replay's client: its canonical form).
    """

    _key_header = ("Authorization", "Bearer ")

    @staticmethod
    def _read(data: Any) -> ChatResponse:
        message = data["choices"][0]["message"]
        content = message.get("content")
        if isinstance(content, list):  # some servers return content parts
            content = "".join(p.get("text", "") for p in content if isinstance(p, dict))
        if not isinstance(content, str):
            raise TypeError(f"choices[0].message.content is {type(content).__name__}")
        return ChatResponse(
            content, _usage(data.get("usage"), "prompt_tokens", "completion_tokens")
        )


def _anthropic_part(part: dict[str, Any]) -> dict[str, Any]:
    if part.get("type") == "image_url":
        url = part["image_url"]["url"]
        # a replay sends the frame by its pixel digest, as the cassette stores it
        if not url.startswith((JPEG_DATA_URL, frames.PIXELS)):
            raise ConfigError(f"image url {url[:40]!r}... is not a base64 JPEG data URL.")
        data = url.removeprefix(JPEG_DATA_URL)
        source = {"type": "base64", "media_type": "image/jpeg", "data": data}
        return {"type": "image", "source": source}
    return {"type": "text", "text": part["text"]}


def to_anthropic(messages: list[dict[str, Any]]) -> tuple[str, list[dict[str, Any]]]:
    """(system prompt, Messages-API messages) from OpenAI-format messages."""
    system = "\n\n".join(m["content"] for m in messages if m["role"] == "system")
    converted = []
    for message in messages:
        if message["role"] != "system":
            content = message["content"]
            parts = [_anthropic_part(p) for p in content] if isinstance(content, list) else content
            converted.append({"role": message["role"], "content": parts})
    return system, converted


class AnthropicClient(_HttpClient):
    """``POST {base_url}/v1/messages`` (Anthropic Messages API).

    :param config: The Anthropic model's registry entry.
    :param base_url: The endpoint, without ``/v1/messages``.
    :param policy: Retries and timeouts, as for :class:`OpenAICompatibleClient`.
    :param transport: A transport replacing the network.
    :param require_key: Whether an unset key is an error.
    :param deadline: Whether each attempt has a deadline, as for :class:`OpenAICompatibleClient`.
    :param encode: The bytes sent for a body, as for :class:`OpenAICompatibleClient`.
    """

    _key_header = ("x-api-key", "")

    @staticmethod
    def _read(data: Any) -> ChatResponse:
        texts = [b["text"] for b in data["content"] if b.get("type") == "text"]
        if not texts:
            raise ValueError("no text block in content")
        usage = _usage(data.get("usage"), "input_tokens", "output_tokens")
        return ChatResponse("".join(texts), usage)


#: Most tokens one reply may report per field (a bound far above any context window).
MAX_USAGE_TOKENS: Final = 100_000_000


def _usage(usage: Any, *names: str) -> Usage:
    """The provider's token counts (absent: 0); a count that is not a whole number in
    [0, :data:`MAX_USAGE_TOKENS`] makes the reply unreadable (ValueError: retried)."""
    counts = [(usage or {}).get(name) or 0 for name in names]
    for name, value in zip(names, counts, strict=True):
        if type(value) is not int or not 0 <= value <= MAX_USAGE_TOKENS:
            raise ValueError(f"usage.{name}={str(value)[:20]} is not a whole number in [0, 1e8]")
    return Usage(*counts)


def _sampling(config: ModelConfig) -> dict[str, Any]:
    return {k: getattr(config, k) for k in SAMPLING_FIELDS if getattr(config, k) is not None}


def build_request(config: ModelConfig, messages: list[dict[str, Any]]) -> ProviderRequest:
    """The path, headers (no key) and JSON body ``config``'s provider is sent for ``messages``;
    key order is fixed: cassettes match on the body.

    :param config: The model's registry entry (provider, model name, sampling settings).
    :param messages: The chat messages, OpenAI-style.
    :returns: The :class:`ProviderRequest` to send.
    """
    if config.provider == "anthropic":
        system, converted = to_anthropic(messages)
        body = {"model": config.model_id, "system": system, "messages": converted}
        body |= _sampling(config) | {"max_tokens": config.max_tokens} | config.extra_body
        pinned = {name.lower() for name in config.extra_headers}
        headers = {} if "anthropic-version" in pinned else {"anthropic-version": ANTHROPIC_VERSION}
        headers |= config.extra_headers
        return ProviderRequest("/v1/messages", headers, body)
    body = {"model": config.model_id, "messages": messages, **_sampling(config)}
    body |= {config.max_tokens_param: config.max_tokens} | config.extra_body
    return ProviderRequest("/chat/completions", dict(config.extra_headers), body)


def make_client(
    config: ModelConfig,
    *,
    base_url: str | None = None,
    policy: RetryPolicy | None = None,
    require_key: bool = True,
    deadline: bool = True,
    encode: Callable[[Any], bytes] = encode_body,
) -> ChatClient:
    """The client for ``config``, sending to ``base_url`` (default: ``config.base_url``; a
    reference agent has none: :func:`pytest_emrd.reference.base_url_of` gives the built-in
    server's); :class:`ConfigError` when the API-key variable is unset, unless
    ``require_key=False``, or when there is no URL.

    :param config: The model's registry entry.
    :param policy: Retries and timeouts; None for the default policy.
    :param require_key: Raise when the API-key variable is unset.
    :param deadline: Give each attempt ``timeout_s``, connect to last byte
        (:class:`DeadlineTransport`); a replay's client needs none.
    :param encode: The bytes sent for a body: its wire JSON, or for a replay's client its
        canonical form (:func:`pytest_emrd.cassette.canonical_body`).
    :param base_url: The endpoint to send to; None for ``config.base_url``.
    :returns: A :class:`ChatClient` ready to send.
    """
    client = AnthropicClient if config.provider == "anthropic" else OpenAICompatibleClient
    base_url = config.base_url if base_url is None else base_url
    if base_url is None:
        raise ConfigError(
            f"model {config.name!r} has no base_url; pass base_url=, for a reference agent "
            "pytest_emrd.reference.base_url_of(config) (the built-in server, started on demand)."
        )
    return client(
        config,
        base_url=base_url,
        policy=policy,
        require_key=require_key,
        deadline=deadline,
        encode=encode,
    )
