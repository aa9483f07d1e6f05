"""What the endpoint says about itself: ``GET /models`` (reachability, served ids, context).

The listing is asked for with the model's key and headers, as the probe will be: HTTP 401 or
403 means the endpoint is up and refuses us, which the ``url`` check reports as a failure
(:attr:`ServerInfo.refused`), never as a pass. vLLM lists each served model with
``max_model_len``, the context length it was started with; that figure is reported as the
server gives it.
"""

from __future__ import annotations

from dataclasses import dataclass
from typing import Any, Final

import httpx

#: Seconds to wait for ``GET /models``: a local server answers at once, a missing one fails.
LIST_TIMEOUT_S: Final = 10.0


@dataclass(frozen=True)
class ServerInfo:
    """The answer to ``GET /models`` (or why there was none)."""

    url: str
    status: int | None
    """HTTP status, ``None`` when the server could not be reached."""
    served: tuple[str, ...] = ()
    """Model ids the listing names (empty when it could not be read)."""
    max_model_len: int | None = None
    """Context length the server reports for our model (vLLM), else ``None``."""
    error: str | None = None
    """Transport error when unreachable."""

    @property
    def reachable(self) -> bool:
        return self.status is not None

    @property
    def refused(self) -> bool:
        """The server answered that our credentials are missing or wrong (401, 403)."""
        return self.status in (401, 403)

    def serves(self, model_id: str) -> bool | None:
        """Whether the listing names ``model_id`` (``models/`` prefixes ignored); ``None``
        when there is no readable listing."""
        if not self.served:
            return None
        return model_id in {s.removeprefix("models/") for s in self.served}


def models_url(provider: str, base_url: str) -> str:
    """The model listing of an endpoint (Anthropic's lives under ``/v1``), joined as the
    clients join their endpoints: after the base path, the base query kept."""
    from pytest_emrd.agent._clients import endpoint_url

    return endpoint_url(base_url, "/v1/models" if provider == "anthropic" else "/models")


def _entries(data: Any) -> list[dict[str, Any]]:
    items = data.get("data") if isinstance(data, dict) else None
    return [i for i in items if isinstance(i, dict)] if isinstance(items, list) else []


def server_info(
    url: str,
    model_id: str,
    *,
    timeout: float = LIST_TIMEOUT_S,
    headers: dict[str, str] | None = None,
) -> ServerInfo:
    """``GET url`` with ``headers`` (the key, when there is one); never raises for a network
    or protocol failure."""
    try:
        response = httpx.get(url, timeout=timeout, headers=headers)
    except httpx.HTTPError as exc:
        return ServerInfo(url, None, error=f"{type(exc).__name__}: {exc}")
    if response.status_code != 200:
        return ServerInfo(url, response.status_code)
    try:
        entries = _entries(response.json())
    except ValueError:
        return ServerInfo(url, 200)
    served = tuple(str(e.get("id")) for e in entries if e.get("id"))
    ours = next((e for e in entries if str(e.get("id")).removeprefix("models/") == model_id), {})
    length = ours.get("max_model_len")
    return ServerInfo(
        url,
        200,
        served=served,
        max_model_len=length if isinstance(length, int) and not isinstance(length, bool) else None,
    )
